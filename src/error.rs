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

    /// A parameter error: `name` had `value`, `expected` says what is valid. The value is
    /// echoed [`shorten`]ed.
    pub fn param(name: impl Into<String>, value: impl std::fmt::Display, expected: impl Into<String>) -> Self {
        Error::InvalidParameter { name: name.into(), value: shorten(&value.to_string()), expected: expected.into() }
    }
}

/// Longest text a message echoes back from the input (characters); longer text is cut.
pub const ECHO_MAX_CHARS: usize = 120;

/// Longest line of a message (characters); longer lines are cut.
pub const LINE_MAX_CHARS: usize = 1000;

/// `text` with every line longer than `max` characters cut there (a TOML syntax error quotes
/// its whole line: a scene with a 200 KB line would be echoed whole). The CLI passes every
/// message through it with [`LINE_MAX_CHARS`].
pub fn shorten_lines(text: &str, max: usize) -> String {
    let lines: Vec<String> = text
        .split('\n')
        .map(|l| {
            let count = l.chars().count();
            if count > max {
                format!("{}… ({count} characters in all)", l.chars().take(max).collect::<String>())
            } else {
                l.to_string()
            }
        })
        .collect();
    lines.join("\n")
}

/// Text echoed back in a message, kept short (docs/robustness.md, "Messages"): every number
/// written with more than 12 characters (`1e300` printed by `f64`'s `Display` is 301 digits) is
/// rewritten with 6 significant digits (`1.00000e300`), and text still longer than
/// [`ECHO_MAX_CHARS`] characters is cut there with `… (N characters in all)`.
pub fn shorten(text: &str) -> String {
    let mut out = String::with_capacity(text.len().min(4 * ECHO_MAX_CHARS));
    let mut token = String::new();
    let flush = |token: &mut String, out: &mut String| {
        match token.parse::<f64>() {
            Ok(v) if token.len() > 12 && v.is_finite() => out.push_str(&format!("{v:.5e}")),
            _ => out.push_str(token),
        }
        token.clear();
    };
    for c in text.chars() {
        let numeric = c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E');
        if numeric && !(token.is_empty() && matches!(c, 'e' | 'E')) {
            token.push(c);
        } else {
            flush(&mut token, &mut out);
            out.push(c);
        }
    }
    flush(&mut token, &mut out);
    let count = out.chars().count();
    if count > ECHO_MAX_CHARS {
        let cut: String = out.chars().take(ECHO_MAX_CHARS).collect();
        return format!("{cut}… ({count} characters in all)");
    }
    out
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
