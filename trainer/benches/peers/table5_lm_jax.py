"""The training peer of the `peers` bench: Carcenac's Levenberg–Marquardt loop for one leaf
module (3 → N → N → 1) on Table 5's torus, written as a Python user would: JAX for the exact
Jacobian of the residuals [Φ(xᵢ), √γ·(∇Φ(xᵢ) + s·nᵢ)] with respect to the weights, numpy for
the loop, float64, one CPU thread.

The objective is the paper's (Table 1), read as the trainer reads it: E_s = (1/2Nₛ)·Σ e² over
the Nₛ = 4·n error terms, weight decay λ per error term (A = JᵀJ/Nₛ + (λ/Nₛ)·I, B = −(Jᵀe +
λV)/Nₛ); each iteration solves (A + μI)·ΔV = B, multiplying μ by θ until the step lowers E_s
(at most up to μ_max), then divides μ by θ; it stops at E_s ≤ threshold.
Points are normalized into the isotropic PCA box [−H/2, H/2]³. Weights start uniform in
[−w₀, w₀], biases at 0.

Usage: python3 table5_lm_jax.py SETS.json
SETS.json (written by the bench): {"settings": {"width", "slope", "gamma", "lambda", "mu0",
"theta", "mu_max", "threshold", "init_range", "box_size", "max_iterations"}, "sets": [{"seed": s,
"points": [[x, y, z], ...], "normals": [[x, y, z], ...]}, ...]}. Prints one line of JSON:
{"runs": [{"points": n, "seed": s, "seconds": t, "iterations": k, "error": E_s}, ...]}; the
JIT compilation of each point count runs once before its runs are timed.
"""

import json
import os
import sys
import time

os.environ.setdefault(
    "XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
)

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

A, GAIN = 1.7159, 2.0 / 3.0


def act(h):
    return A * jnp.tanh(GAIN * h)


def unpack(v, n):
    at = 0

    def take(size, shape):
        nonlocal at
        out = v[at : at + size].reshape(shape)
        at += size
        return out

    wa, ba = take(3 * n, (n, 3)), take(n, (n,))
    wb, bb = take(n * n, (n, n)), take(n, (n,))
    wo, bo = take(n, (n,)), take(1, ())
    return wa, ba, wb, bb, wo, bo


def phi(v, x, n):
    wa, ba, wb, bb, wo, bo = unpack(v, n)
    a = act(wa @ x + ba)
    b = act(wb @ a + bb)
    return act(wo @ b + bo)


def make_residuals(n, slope, gamma):
    value_grad = jax.vmap(jax.value_and_grad(phi, argnums=1), in_axes=(None, 0, None))
    root_gamma = np.sqrt(gamma)

    def residuals(v, x, normals):
        value, gradient = value_grad(v, x, n)
        return jnp.concatenate(
            [value, (root_gamma * (gradient + slope * normals)).reshape(-1)]
        )

    return jax.jit(residuals), jax.jit(jax.jacfwd(residuals))


def normalize(points, normals, box_size):
    """The isotropic PCA box: the longest axis fills [−H/2, H/2]; normals rotate along."""
    center = points.mean(axis=0)
    _, _, axes = np.linalg.svd(points - center, full_matrices=False)
    local = (points - center) @ axes.T
    scale = (box_size / 2) / np.abs(local).max()
    return local * scale, normals @ axes.T


def train(x, normals, settings, seed, functions):
    n = settings["width"]
    residuals, jacobian = functions
    size = 3 * n + n + n * n + n + n + 1
    rng = np.random.default_rng(seed)
    w0 = settings["init_range"]
    v = rng.uniform(-w0, w0, size)
    # Biases start at 0.
    for start, length in [(3 * n, n), (4 * n + n * n, n), (size - 1, 1)]:
        v[start : start + length] = 0.0
    # Nₛ: every error term, Φ and the three gradient components of each control point.
    count = 4 * len(x)
    lam, mu, theta = settings["lambda"], settings["mu0"], settings["theta"]

    def errors(v):
        e = np.asarray(residuals(v, x, normals))
        return e, 0.5 * float(e @ e) / count

    e, e_s = errors(v)
    iterations = 0
    while e_s > settings["threshold"] and iterations < settings["max_iterations"]:
        j = np.asarray(jacobian(v, x, normals))
        a = j.T @ j / count + (lam / count) * np.eye(size)
        b = -(j.T @ e + lam * v) / count
        # μ grows by θ until a step lowers E_s; after it, μ shrinks by θ.
        while mu <= settings["mu_max"]:
            trial = v + np.linalg.solve(a + mu * np.eye(size), b)
            e_t, e_s_t = errors(trial)
            if np.isfinite(e_s_t) and e_s_t <= e_s:
                v, e, e_s = trial, e_t, e_s_t
                break
            mu *= theta
        else:
            break
        mu /= theta
        iterations += 1
    return iterations, e_s


def main():
    with open(sys.argv[1]) as f:
        request = json.load(f)
    settings = request["settings"]
    compiled = {}
    runs = []
    for entry in request["sets"]:
        points = np.asarray(entry["points"], dtype=np.float64)
        normals = np.asarray(entry["normals"], dtype=np.float64)
        x, m = normalize(points, normals, settings["box_size"])
        count = len(x)
        if count not in compiled:
            functions = make_residuals(settings["width"], settings["slope"], settings["gamma"])
            # Compile for this point count before any run is timed.
            train(x, m, dict(settings, max_iterations=1), 0, functions)
            compiled[count] = functions
        start = time.perf_counter()
        iterations, error = train(x, m, settings, entry["seed"], compiled[count])
        seconds = time.perf_counter() - start
        runs.append(
            {
                "points": count,
                "seed": entry["seed"],
                "seconds": seconds,
                "iterations": iterations,
                "error": error,
            }
        )
    print(json.dumps({"runs": runs}))


if __name__ == "__main__":
    main()
