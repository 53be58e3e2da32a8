//! The parsing context: errors naming the file and the key, overrides, deserializing tables.

use std::fmt::Display;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use toml::{Table, Value};

use super::overrides::{parse_override_value, Override};
use crate::error::{Error, Result};

// ---------------------------------------------------------------------------------------------
// Building the scene

/// Parsing context: names the file in errors, resolves paths, remembers overrides.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a str,
    pub(super) base_dir: &'a Path,
    pub(super) overrides: Vec<Override>,
}

/// `a.b` (or `b` when `a` is empty).
fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

/// `[a, b, c]` with each number in its shortest form.
pub(super) fn fmt_list(v: &[f64]) -> String {
    let items: Vec<String> = v.iter().map(|x| x.to_string()).collect();
    format!("[{}]", items.join(", "))
}

impl Ctx<'_> {
    /// An [`Error::SceneFile`] for `key` (None: not about one key), noting the override that set
    /// the key, if one did.
    pub(super) fn err(&self, key: Option<&str>, message: impl Into<String>) -> Error {
        let mut message = message.into();
        if let Some(k) = key {
            let covers = |p: &str| p == k || k.starts_with(&format!("{p}.")) || p.starts_with(&format!("{k}."));
            if let Some(o) = self.overrides.iter().rev().find(|o| covers(&o.key)) {
                message.push_str(&format!(" (set by --set {})", crate::error::shorten(&o.text)));
            }
        }
        Error::SceneFile { file: self.file.to_string(), key: key.map(str::to_string), message }
    }

    /// `invalid key = value: expected …`.
    pub(super) fn invalid(&self, key: &str, value: impl Display, expected: impl Display) -> Error {
        let value = crate::error::shorten(&value.to_string());
        self.err(Some(key), format!("invalid {key} = {value}: expected {expected}"))
    }

    /// Wraps an error from another module (height-field loader, generator, model validation):
    /// an [`Error::InvalidParameter`] whose name is a scene key keeps it as the key; anything
    /// else is reported under `key`.
    pub(super) fn wrap(&self, key: &str, e: Error) -> Error {
        match &e {
            Error::InvalidParameter { name, .. } if name == key || name.starts_with(&format!("{key}.")) => {
                self.err(Some(name), e.to_string())
            }
            _ => self.err(Some(key), format!("{key}: {e}")),
        }
    }

    pub(super) fn resolve(&self, p: &Path) -> PathBuf {
        self.base_dir.join(p)
    }

    pub(super) fn parse_override(&self, text: &str) -> Result<Override> {
        let bad = |why: &str| {
            self.err(
                None,
                format!("invalid override `--set {text}`: {why}; expected key.path=value, e.g. gi.azimuths=64"),
            )
        };
        let Some((key, value)) = text.split_once('=') else { return Err(bad("no `=`")) };
        let key = key.trim();
        let segments: Vec<String> = key.split('.').map(str::to_string).collect();
        if let Some(s) = segments
            .iter()
            .find(|s| s.is_empty() || !s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'))
        {
            return Err(bad(&format!("`{s}` in `{key}` is not a bare key (letters, digits, _ and -)")));
        }
        Ok(Override {
            key: key.to_string(),
            segments,
            value: parse_override_value(value.trim()),
            text: text.to_string(),
        })
    }

    /// Deserializes `table` (at `path`) into `T`, attributing any error to one key: serde's
    /// unknown-field message names it; otherwise each key is tried on its own (every field of
    /// the raw types is optional) and the first that fails is the culprit.
    pub(super) fn de_table<T: DeserializeOwned>(&self, table: &Table, path: &str) -> Result<T> {
        let e = match T::deserialize(Value::Table(table.clone())) {
            Ok(t) => return Ok(t),
            Err(e) => e,
        };
        let msg = e.message();
        if let Some((name, tail)) = msg.strip_prefix("unknown field `").and_then(|r| r.split_once('`')) {
            let key = join(path, name);
            let tail = tail.trim_start_matches(',').trim().replace('`', "").replacen(
                "expected one of ",
                "expected one of: ",
                1,
            );
            let where_ = if path.is_empty() { "at the top level".to_string() } else { format!("in [{path}]") };
            let detail = if tail.is_empty() { where_ } else { format!("{where_}; {tail}") };
            return Err(self.err(Some(&key), format!("unknown key `{key}` ({detail})")));
        }
        for (k, v) in table {
            let one: Table = std::iter::once((k.clone(), v.clone())).collect();
            if let Err(e1) = T::deserialize(Value::Table(one)) {
                let key = join(path, k);
                let hint = if key == "key_light" && e1.message().contains("expected a sequence") {
                    " (write each key light as a [[key_light]] table)"
                } else {
                    ""
                };
                return Err(self.err(Some(&key), format!("{key}: {}{hint}", e1.message())));
            }
        }
        let key = (!path.is_empty()).then_some(path);
        Err(self.err(key, if path.is_empty() { msg.to_string() } else { format!("{path}: {msg}") }))
    }

    pub(super) fn de_opt<T: DeserializeOwned + Default>(&self, table: Option<&Table>, path: &str) -> Result<T> {
        table.map_or_else(|| Ok(T::default()), |t| self.de_table(t, path))
    }

    pub(super) fn finite_f32(&self, key: &str, v: f64, ok: bool, expected: &str) -> Result<f32> {
        if ok && v.is_finite() && (v as f32).is_finite() {
            Ok(v as f32)
        } else {
            Err(self.invalid(key, v, expected))
        }
    }

    pub(super) fn rgb(&self, key: &str, v: [f64; 3], lo: f64, hi: f64, expected: &str) -> Result<[f64; 3]> {
        if v.iter().all(|x| x.is_finite() && *x >= lo && *x <= hi && (*x as f32).is_finite()) {
            Ok(v)
        } else {
            Err(self.invalid(key, fmt_list(&v), expected))
        }
    }
}
