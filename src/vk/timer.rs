//! Named GPU stage timing: each scope writes a timestamp pair; after the frame's fence,
//! [`StageTimer::timings`] returns `[(stage, ms)]` scaled by `timestampPeriod`.

use ash::vk;

use super::Context;
use crate::error::{Error, Result, VkCall};

/// A timestamp query pool holding up to `capacity` named scopes per frame.
pub struct StageTimer {
    pool: vk::QueryPool,
    capacity: u32,
    names: Vec<String>,
    overflow: bool,
    period_ns: f64,
    valid_bits: u32,
}

impl StageTimer {
    /// Creates a pool for `capacity` scopes. On a queue family without timestamps the timer
    /// still records scope names (and debug labels), and [`StageTimer::timings`] says so.
    pub fn new(ctx: &Context, capacity: u32) -> Result<Self> {
        let info = ctx.info();
        let mut pool = vk::QueryPool::null();
        if info.timestamp_valid_bits > 0 {
            let ci = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity * 2);
            pool = unsafe { ctx.device().create_query_pool(&ci, None) }.vk("vkCreateQueryPool")?;
            ctx.set_name(pool, "hfgi.stage_timer");
        }
        Ok(Self {
            pool,
            capacity,
            names: Vec::new(),
            overflow: false,
            period_ns: info.timestamp_period as f64,
            valid_bits: info.timestamp_valid_bits,
        })
    }

    /// Whether the queue can time stages at all.
    pub fn supported(&self) -> bool {
        self.pool != vk::QueryPool::null()
    }

    /// Starts a frame: resets the queries (recorded into `cmd`) and forgets old names.
    pub fn reset(&mut self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.names.clear();
        self.overflow = false;
        if self.supported() {
            unsafe { ctx.device().cmd_reset_query_pool(cmd, self.pool, 0, self.capacity * 2) };
        }
    }

    /// Opens a scope; returns its index for [`StageTimer::end`].
    pub fn begin(&mut self, ctx: &Context, cmd: vk::CommandBuffer, name: &str) -> usize {
        let idx = self.names.len();
        self.names.push(name.to_string());
        if self.supported() && (idx as u32) < self.capacity {
            unsafe {
                ctx.device().cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, 2 * idx as u32)
            };
        } else if self.supported() {
            self.overflow = true;
        }
        idx
    }

    /// Closes scope `idx`.
    pub fn end(&mut self, ctx: &Context, cmd: vk::CommandBuffer, idx: usize) {
        if self.supported() && (idx as u32) < self.capacity {
            unsafe {
                ctx.device().cmd_write_timestamp2(
                    cmd,
                    vk::PipelineStageFlags2::ALL_COMMANDS,
                    self.pool,
                    2 * idx as u32 + 1,
                )
            };
        }
    }

    /// Names of the scopes recorded since the last reset, in order.
    pub fn stage_names(&self) -> &[String] {
        &self.names
    }

    /// `[(stage name, milliseconds)]` of the last frame. Call after its fence signalled.
    pub fn timings(&self, ctx: &Context) -> Result<Vec<(String, f64)>> {
        if !self.supported() {
            return Err(Error::Unsupported(format!(
                "queue family {} of '{}' has no timestamp support (timestampValidBits = 0); no stage timings",
                ctx.queue_family(),
                ctx.info().name
            )));
        }
        if self.overflow {
            return Err(Error::Unsupported(format!(
                "{} scopes recorded but the timer holds {}; create it with a larger capacity",
                self.names.len(),
                self.capacity
            )));
        }
        if self.names.is_empty() {
            return Ok(Vec::new());
        }
        let mut raw = vec![0u64; self.names.len() * 2];
        unsafe {
            ctx.device().get_query_pool_results(
                self.pool,
                0,
                &mut raw,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .vk("vkGetQueryPoolResults")?;
        let mask = if self.valid_bits >= 64 { u64::MAX } else { (1u64 << self.valid_bits) - 1 };
        Ok(self
            .names
            .iter()
            .enumerate()
            .map(|(i, n)| {
                let ticks = (raw[2 * i + 1] & mask).wrapping_sub(raw[2 * i] & mask) & mask;
                (n.clone(), ticks as f64 * self.period_ns * 1e-6)
            })
            .collect())
    }

    /// Destroys the query pool.
    pub fn destroy(&mut self, ctx: &Context) {
        if self.supported() {
            unsafe { ctx.device().destroy_query_pool(self.pool, None) };
            self.pool = vk::QueryPool::null();
        }
    }
}
