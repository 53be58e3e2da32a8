//! CPU (f64) twins of the GPU stages, same algorithm and parameters, used by the tests.

pub mod direct;
pub mod indirect;
pub mod cap;
pub mod pyramid;
pub mod ray;
pub mod truth;
pub mod water;
