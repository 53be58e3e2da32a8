//! f64 reference math.
//!
//! Everything here follows `CONVENTIONS.md` ("Spherical harmonics"): real orthonormal SH without
//! the Condon–Shortley phase, order `n` = bands `l = 0..n−1`, `n²` coefficients at index
//! `k = l(l+1) + m`; normalised Legendre polynomials `P̂_l(z) = sqrt((2l+1)/2)·P_l(z)`.
//! Equation numbers refer to Nowrouzezahrai & Snyder, "Fast Global Illumination on Dynamic
//! Height Fields", EGSR 2009.
pub mod azimuth;
pub mod bspline;
pub mod elevation;
pub mod legendre;
pub mod logcap;
pub mod nlp;
pub mod overlap;
pub mod quadrature;
pub mod rgbe;
pub mod sh;
pub mod shexp;
pub mod triple;
pub mod wedge;
pub mod zh;

pub use wedge::Mat;

/// Largest SH order accepted by this module (bands `0..16`).
pub const MAX_ORDER: usize = 16;

/// Panics (programmer error) unless `1 <= n <= MAX_ORDER`.
#[inline]
pub(crate) fn check_order(n: usize) {
    assert!((1..=MAX_ORDER).contains(&n), "SH/NLP order n = {n} outside 1..={MAX_ORDER}");
}
