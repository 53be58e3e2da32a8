//! The rules both the GPU passes ([`crate::frame`]) and the CPU twins ([`crate::reference`])
//! follow: pure functions and layouts over [`crate::math`] and [`crate::scene`], no Vulkan. The
//! twins depend on these, on `math` and on `scene` only, never on `frame`, so a rule is written
//! once and a GPU-vs-twin test cannot share a bug hidden in GPU-side code.

pub mod layout;
pub mod lighting;
pub mod scene;
