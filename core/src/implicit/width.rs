//! Width-specialized evaluation: the hidden width N is a run-time property of a blob, but the
//! hot loops are far cheaper when it is a compile-time constant (rows unrolled, a layer's inputs
//! in registers, no bounds checks, layers sized to the model so nothing is zeroed).
//!
//! Every evaluation is written once, generic over a capacity `N` and a flag `EXACT`.
//! [`at_width!`] instantiates it with `N` = the model's width and `EXACT = true` for the widths
//! in [`SPECIALIZED`], and with `N` = [`MAX_WIDTH`](super::MAX_WIDTH) and `EXACT = false` (the width read at run
//! time) for every other width. Both compute exactly the same operations in the same order, so
//! the results are bit-identical.

/// The widths compiled as constants: Carcenac's N = 9 (the trainer's default) and the small
/// N = 4, where run-time loop set-up would weigh most. Every other width runs the same code with
/// run-time loop bounds.
pub const SPECIALIZED: [usize; 2] = [4, 9];

/// `at_width!(width, receiver.method::<L>(args…))` calls `receiver.method::<L, N, EXACT>(args…)`
/// specialized for `width` (`N = width`, `EXACT = true`) when that is one of [`SPECIALIZED`],
/// generic (`N` = [`MAX_WIDTH`](super::MAX_WIDTH), `EXACT = false`) otherwise.
macro_rules! at_width {
    ($width:expr, $receiver:ident . $method:ident :: < $lanes:ident > ( $($arg:expr),* )) => {
        match $width {
            4 => $receiver.$method::<$lanes, 4, true>($($arg),*),
            9 => $receiver.$method::<$lanes, 9, true>($($arg),*),
            _ => $receiver.$method::<$lanes, { $crate::implicit::MAX_WIDTH }, false>($($arg),*),
        }
    };
}
pub(crate) use at_width;

/// The width an instantiation evaluates at: `N` when `EXACT` (a constant the compiler
/// propagates), else `model_width` (at most `N`).
#[inline(always)]
pub(crate) fn width<const N: usize, const EXACT: bool>(model_width: usize) -> usize {
    if EXACT { N } else { model_width.min(N) }
}

#[cfg(test)]
mod tests {
    use super::SPECIALIZED;
    use crate::implicit::MAX_WIDTH;

    /// Reports how [`at_width!`] instantiated it.
    struct Probe;

    impl Probe {
        fn run<const L: usize, const N: usize, const EXACT: bool>(&self) -> (usize, usize, bool) {
            (L, N, EXACT)
        }
    }

    #[test]
    fn specialized_widths_are_dispatched_exactly() {
        const L: usize = 1;
        let probe = Probe;
        for width in 1..=MAX_WIDTH {
            let expected = if SPECIALIZED.contains(&width) {
                (L, width, true)
            } else {
                (L, MAX_WIDTH, false)
            };
            assert_eq!(
                at_width!(width, probe.run::<L>()),
                expected,
                "width {width}"
            );
        }
    }
}
