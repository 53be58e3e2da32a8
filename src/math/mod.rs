//! f64 reference math.
pub mod bspline;
