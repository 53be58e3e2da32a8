//! Scenes and height fields.
pub mod heightfield;
pub use heightfield::HeightField;
