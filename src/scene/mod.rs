//! Scenes and height fields: the type, procedural generators and file loaders.
pub mod animated;
pub mod boulders;
pub mod day;
pub mod envmap;
pub mod file;
pub mod generators;
pub mod geotiff;
pub mod heightfield;
pub mod load;
pub mod model;
pub use heightfield::HeightField;
