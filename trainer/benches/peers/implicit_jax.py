"""The JAX peer of the `peers` bench: Φ and ∇Φ of a neurosurf implicit model, written as a
Python user would, `jax.jit(jax.vmap(jax.value_and_grad(phi)))` in float32 on one CPU thread.

Usage: python3 implicit_jax.py MODEL.json
MODEL.json (written by the bench): {"width": N, "kinds": ["leaf"|"node", ...] in post-order,
"params": [...] in the core's layout, "guards": [[cx, cy, cz, rho, a], ...],
"points": [[x, y, z], ...]}. Prints one line of JSON: {"ns_per_point": t, "phi": [...]}
(the field at the first 8 points, so the bench can check that both compute the same model).
"""

import json
import os
import sys
import time

os.environ.setdefault(
    "XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
)

import jax  # noqa: E402
import jax.numpy as jnp  # noqa: E402
import numpy as np  # noqa: E402

A, GAIN = 1.7159, 2.0 / 3.0


def act(h):
    return A * jnp.tanh(GAIN * h)


def layouts(width, kinds):
    """Per module: (offset, kind), as the core lays the parameters out."""
    offset, out = 0, []
    for kind in kinds:
        inputs = 3 if kind == "leaf" else 2 * width + 3
        size = 12 + width * inputs + width + width * width + width + width + 1
        out.append((offset, kind, inputs))
        offset += size
    return out


def build(model):
    width, kinds = model["width"], model["kinds"]
    params = np.asarray(model["params"], dtype=np.float32)
    modules = []
    for offset, kind, inputs in layouts(width, kinds):
        p, at = params, offset

        def take(n, shape=None):
            nonlocal at
            v = jnp.asarray(p[at : at + n])
            at += n
            return v.reshape(shape) if shape else v

        c, axes = take(3), take(9, (3, 3))
        wa, ba = take(width * inputs, (width, inputs)), take(width)
        wb, bb = take(width * width, (width, width)), take(width)
        wo, bo = take(width), take(1)
        modules.append((kind, c, axes, wa, ba, wb, bb, wo, bo))
    guards = jnp.asarray(np.asarray(model["guards"], dtype=np.float32).reshape(-1, 5))

    def phi(x):
        stack = []
        for kind, c, axes, wa, ba, wb, bb, wo, bo in modules:
            xn = axes @ (x - c)
            if kind == "leaf":
                inp = xn
            else:
                right, left = stack.pop(), stack.pop()
                inp = jnp.concatenate([left, right, xn])
            b = act(wb @ act(wa @ inp + ba) + bb)
            stack.append(b)
            out = act(wo @ b + bo[0])
        value = out
        if guards.shape[0]:
            d = (x[None, :] - guards[:, :3]) * guards[:, 3:4]
            t2 = jnp.sum(d * d, axis=1)
            inside = jnp.all(jnp.abs(d) < 1.0, axis=1) & (t2 < 1.0)
            u = 1.0 - t2
            value = value + jnp.sum(jnp.where(inside, guards[:, 4] * u * u * u, 0.0))
        return value

    return jax.jit(jax.vmap(jax.value_and_grad(phi)))


def main():
    model = json.load(open(sys.argv[1]))
    points = jnp.asarray(np.asarray(model["points"], dtype=np.float32))
    f = build(model)
    value, grad = f(points)
    value.block_until_ready()
    best = float("inf")
    for _ in range(5):
        start = time.perf_counter()
        for _ in range(5):
            value, grad = f(points)
            grad.block_until_ready()
        best = min(best, (time.perf_counter() - start) / (5 * points.shape[0]))
    print(json.dumps({"ns_per_point": best * 1e9, "phi": [float(v) for v in value[:8]]}))


if __name__ == "__main__":
    main()
