//! Test helpers shared by the workspace's tests. Never a runtime dependency.

/// Asserts that two `f64` values (or two equally long slices of `f64`) are close:
/// `|a - b| <= abs + rel * max(|a|, |b|)`, element by element.
///
/// ```
/// testkit::assert_close!(1.0, 1.0 + 1e-13, rel = 1e-12);
/// testkit::assert_close!(0.0, 1e-15, abs = 1e-14);
/// testkit::assert_close!([1.0, 2.0], [1.0, 2.0 + 1e-12], rel = 1e-11, abs = 0.0);
/// ```
#[macro_export]
macro_rules! assert_close {
    ($a:expr, $b:expr, rel = $rel:expr) => {
        $crate::assert_close!($a, $b, rel = $rel, abs = 0.0)
    };
    ($a:expr, $b:expr, abs = $abs:expr) => {
        $crate::assert_close!($a, $b, rel = 0.0, abs = $abs)
    };
    ($a:expr, $b:expr, rel = $rel:expr, abs = $abs:expr) => {{
        let (a, b) = ($a, $b);
        $crate::check_close(
            $crate::AsF64Slice::as_f64_slice(&a),
            $crate::AsF64Slice::as_f64_slice(&b),
            $rel,
            $abs,
        )
        .unwrap_or_else(|msg| {
            panic!(
                "assert_close!({}, {}) failed: {}",
                stringify!($a),
                stringify!($b),
                msg
            )
        });
    }};
}

/// Compares two slices element by element; returns a message naming the first offending
/// index when they are not close.
pub fn check_close(a: &[f64], b: &[f64], rel: f64, abs: f64) -> Result<(), String> {
    if a.len() != b.len() {
        return Err(format!("lengths differ: {} vs {}", a.len(), b.len()));
    }
    for (i, (&x, &y)) in a.iter().zip(b).enumerate() {
        let tol = abs + rel * x.abs().max(y.abs());
        let ok = (x - y).abs() <= tol || (x.is_nan() && y.is_nan());
        if !ok {
            return Err(format!(
                "at index {i}: {x:e} vs {y:e}, |diff| = {:e} > tol {tol:e}",
                (x - y).abs()
            ));
        }
    }
    Ok(())
}

/// Runs `f` on a rayon pool of `threads` threads (the thread-count independence tests).
///
/// ```
/// assert_eq!(testkit::with_threads(3, rayon::current_num_threads), 3);
/// ```
pub fn with_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a rayon thread pool")
        .install(f)
}

/// Largest difference of one coordinate between two point sets of the same numbering
/// (max over points and components of |p_k − q_k|).
pub fn max_coordinate_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    assert_eq!(a.len(), b.len(), "point sets of different lengths");
    a.iter()
        .zip(b)
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}

/// Views a value as a slice of `f64` for [`assert_close!`].
pub trait AsF64Slice {
    /// The values as a slice.
    fn as_f64_slice(&self) -> &[f64];
}

impl AsF64Slice for f64 {
    fn as_f64_slice(&self) -> &[f64] {
        std::slice::from_ref(self)
    }
}
impl<const N: usize> AsF64Slice for [f64; N] {
    fn as_f64_slice(&self) -> &[f64] {
        self
    }
}
impl AsF64Slice for [f64] {
    fn as_f64_slice(&self) -> &[f64] {
        self
    }
}
impl AsF64Slice for Vec<f64> {
    fn as_f64_slice(&self) -> &[f64] {
        self
    }
}
impl<T: AsF64Slice + ?Sized> AsF64Slice for &T {
    fn as_f64_slice(&self) -> &[f64] {
        (**self).as_f64_slice()
    }
}

#[cfg(test)]
mod tests {
    use super::check_close;

    #[test]
    fn detects_difference() {
        assert!(check_close(&[1.0], &[1.1], 1e-3, 0.0).is_err());
        assert!(check_close(&[1.0], &[1.0], 0.0, 0.0).is_ok());
        assert!(check_close(&[1.0], &[1.0, 2.0], 1.0, 1.0).is_err());
    }
}
