//! Recording context handed to passes: the caller's command buffer plus named scopes that
//! drive timestamps and debug-utils labels.

use std::ffi::CString;

use ash::vk;

use super::{Context, StageTimer};

/// Wraps a caller-provided command buffer in the recording state.
pub struct Recorder<'a> {
    pub ctx: &'a Context,
    pub cmd: vk::CommandBuffer,
    timer: Option<&'a mut StageTimer>,
    stages: Vec<String>,
}

impl<'a> Recorder<'a> {
    /// Starts recording into `cmd` (already begun by the caller). With a timer, its queries are
    /// reset first, so one timer serves one command buffer per frame.
    pub fn new(ctx: &'a Context, cmd: vk::CommandBuffer, mut timer: Option<&'a mut StageTimer>) -> Self {
        if let Some(t) = timer.as_deref_mut() {
            t.reset(ctx, cmd);
        }
        Self { ctx, cmd, timer, stages: Vec::new() }
    }

    /// Runs `f` inside a named scope: a debug-utils label and, with a timer, a timestamp pair.
    pub fn scope<R>(&mut self, name: &str, f: impl FnOnce(&Context, vk::CommandBuffer) -> R) -> R {
        self.stages.push(name.to_string());
        let label = CString::new(name).unwrap_or_default();
        if let Some(du) = self.ctx.debug_utils() {
            let l = vk::DebugUtilsLabelEXT::default().label_name(&label);
            unsafe { du.cmd_begin_debug_utils_label(self.cmd, &l) };
        }
        let idx = self.timer.as_deref_mut().map(|t| t.begin(self.ctx, self.cmd, name));
        let r = f(self.ctx, self.cmd);
        if let (Some(t), Some(i)) = (self.timer.as_deref_mut(), idx) {
            t.end(self.ctx, self.cmd, i);
        }
        if let Some(du) = self.ctx.debug_utils() {
            unsafe { du.cmd_end_debug_utils_label(self.cmd) };
        }
        r
    }

    /// Names of the scopes recorded so far, in order.
    pub fn stages(&self) -> &[String] {
        &self.stages
    }
}
