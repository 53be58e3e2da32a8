//! The library's one error type. Every message names the file or parameter, the value found
//! and what was expected.

use std::path::PathBuf;

use ash::vk;

/// Errors returned by hfgi. Never a panic on bad input.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An operating-system I/O error on a named file.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// A file that could not be decoded (truncated, empty, wrong format, wrong channels...).
    #[error("{}: {what}", path.display())]
    Format { path: PathBuf, what: String },

    /// A height field whose size is outside `[2, max]` on either axis.
    #[error("{source_name}: height field is {width}×{height}; expected at least 2×2 and at most {max}×{max} (the device's maxImageDimension2D)")]
    FieldSize { source_name: String, width: usize, height: usize, max: u32 },

    /// A non-finite value in a height field (or other numeric input).
    #[error("{source_name}: value {value} at (x={x}, y={y}) is not finite; expected finite heights")]
    NonFinite { source_name: String, x: usize, y: usize, value: f32 },

    /// A parameter outside its valid range.
    #[error("invalid {name} = {value}: expected {expected}")]
    InvalidParameter { name: String, value: String, expected: String },

    /// An invalid scene file or `--set` override (`scene::file`): `file` is the scene file's
    /// name, `key` the offending key path (`gi.azimuths`, `key_light.0.radiance`; `None` for a
    /// TOML syntax error or a malformed override) and `message` says what was found and what is
    /// valid.
    #[error("{file}: {message}")]
    SceneFile { file: String, key: Option<String>, message: String },

    /// A Vulkan call failed.
    #[error("Vulkan: {call} failed with {result:?}")]
    Vulkan { call: &'static str, result: vk::Result },

    /// The Vulkan loader could not be opened.
    #[error("Vulkan loader not found ({0}); install libvulkan1 and a driver (e.g. mesa-vulkan-drivers)")]
    Loader(String),

    /// No physical device satisfied the requirements or the `HFGI_DEVICE` filter.
    #[error("no suitable Vulkan device: {0}")]
    NoDevice(String),

    /// GPU memory allocation failed.
    #[error("GPU allocation '{name}' ({size} bytes) failed: {reason}")]
    Allocation { name: String, size: u64, reason: String },

    /// The device or queue cannot do what was asked (e.g. no timestamp support).
    #[error("unsupported: {0}")]
    Unsupported(String),

    /// The Vulkan validation layer reported messages (only with `HFGI_VALIDATION=1`).
    #[error("the Vulkan validation layer reported {} message(s):\n{}", messages.len(), messages.join("\n"))]
    Validation { messages: Vec<String> },
}

/// Result alias used across the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Wraps an `std::io::Error` with the path it happened on.
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Error::Io { path: path.into(), source }
    }

    /// A decode/format error for `path`.
    pub fn format(path: impl Into<PathBuf>, what: impl Into<String>) -> Self {
        Error::Format { path: path.into(), what: what.into() }
    }

    /// A parameter error: `name` had `value`, `expected` says what is valid.
    pub fn param(name: impl Into<String>, value: impl std::fmt::Display, expected: impl Into<String>) -> Self {
        Error::InvalidParameter { name: name.into(), value: value.to_string(), expected: expected.into() }
    }
}

/// Maps a `vk::Result` into [`Error::Vulkan`] naming the call.
pub(crate) trait VkCall<T> {
    fn vk(self, call: &'static str) -> Result<T>;
}

impl<T> VkCall<T> for std::result::Result<T, vk::Result> {
    fn vk(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vulkan { call, result })
    }
}
