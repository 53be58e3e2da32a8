//! Progress of long library work (today: projecting a large environment map to SH), reported
//! through a callback that the application installs. The library draws nothing itself; the
//! `hfgi` CLI installs a hook that draws a progress bar on a terminal.

use std::sync::RwLock;

/// One report: `done` of `total` units of `task` are finished (`done == total` ends it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Progress<'a> {
    pub task: &'a str,
    pub done: u64,
    pub total: u64,
}

/// A progress callback.
pub type Hook = Box<dyn Fn(&Progress) + Send + Sync>;

static HOOK: RwLock<Option<Hook>> = RwLock::new(None);

/// Installs `hook` for the whole process (`None` removes it).
pub fn set_hook(hook: Option<Hook>) {
    if let Ok(mut h) = HOOK.write() {
        *h = hook;
    }
}

/// Reports progress to the installed hook, if any.
pub(crate) fn report(task: &str, done: u64, total: u64) {
    if let Ok(h) = HOOK.read() {
        if let Some(f) = h.as_ref() {
            f(&Progress { task, done, total });
        }
    }
}
