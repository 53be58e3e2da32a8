//! CPU (f64) twins of the GPU stages, same algorithm and parameters, used by the tests.

pub mod blockers;
pub mod cap;
pub mod direct;
pub mod indirect;
pub mod local;
pub mod local_truth;
pub mod max;
pub mod pyramid;
pub mod ray;
pub mod sh_eval;
pub mod sweep;
pub mod tangent;
pub mod truth;
pub mod water;
pub mod work;
