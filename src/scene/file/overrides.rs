//! `--set key.path=value` overrides: parsing the value and setting it in the document.

use toml::{Table, Value};

// ---------------------------------------------------------------------------------------------
// Overrides

/// One parsed `--set key.path=value`.
pub(super) struct Override {
    /// `key.path` as written (trimmed).
    pub(super) key: String,
    pub(super) segments: Vec<String>,
    pub(super) value: Value,
    /// The whole override as given, for messages.
    pub(super) text: String,
}

/// Parses an override's value text as a TOML value, else takes it as a string.
pub(super) fn parse_override_value(text: &str) -> Value {
    match toml::from_str::<Table>(&format!("v = {text}")) {
        Ok(mut t) if t.len() == 1 => t.remove("v").unwrap_or_else(|| Value::String(text.to_string())),
        _ => Value::String(text.to_string()),
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a float",
        Value::Boolean(_) => "a boolean",
        Value::Datetime(_) => "a date-time",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

/// The element `seg` of `cur` (a table key or an array index), created if missing: a table,
/// or an array when `array_next` (the following segment is an index).
fn child_mut<'a>(
    cur: &'a mut Value,
    seg: &str,
    path: &str,
    array_next: bool,
) -> std::result::Result<&'a mut Value, String> {
    let fresh = || if array_next { Value::Array(Vec::new()) } else { Value::Table(Table::new()) };
    match cur {
        Value::Table(t) => Ok(t.entry(seg.to_string()).or_insert_with(fresh)),
        Value::Array(a) => {
            let i = array_index(seg, path, a.len())?;
            if i == a.len() {
                a.push(fresh());
            }
            Ok(&mut a[i])
        }
        other => Err(format!("cannot set below `{path}`: it is {}, not a table or array", type_name(other))),
    }
}

/// Index `seg` into an array of `len` elements at `path`; `len` itself means "append".
fn array_index(seg: &str, path: &str, len: usize) -> std::result::Result<usize, String> {
    let i: usize = seg
        .parse()
        .map_err(|_| format!("`{path}` is an array: expected a numeric index 0..={len} after it, found `{seg}`"))?;
    if i > len {
        return Err(format!(
            "index {i} is past the end of `{path}` ({len} element(s)): use 0..{len} to change one or {len} to append one"
        ));
    }
    Ok(i)
}

/// Sets `root[segments…] = value`, creating missing tables/arrays.
pub(super) fn set_path(root: &mut Value, segments: &[String], value: Value) -> std::result::Result<(), String> {
    let Some((last, parents)) = segments.split_last() else { return Err("empty key".into()) };
    let mut cur = root;
    for (i, seg) in parents.iter().enumerate() {
        let array_next = segments[i + 1].parse::<usize>().is_ok();
        let path = segments[..i].join(".");
        cur = child_mut(cur, seg, if path.is_empty() { seg } else { &path }, array_next)?;
    }
    let parent = parents.join(".");
    match cur {
        Value::Table(t) => {
            t.insert(last.clone(), value);
            Ok(())
        }
        Value::Array(a) => {
            let i = array_index(last, &parent, a.len())?;
            if i == a.len() {
                a.push(value);
            } else {
                a[i] = value;
            }
            Ok(())
        }
        other => Err(format!("cannot set `{last}` in `{parent}`: it is {}, not a table or array", type_name(other))),
    }
}
