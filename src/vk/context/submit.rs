//! [`Context`]'s queue work: the blocking submit helper and the creation batch (docs/
//! integration.md §1: creation submits once, nothing after it).

use ash::vk;

use super::Context;
use crate::error::{Error, Result, VkCall};

/// A transfer command recorded later, into the batch's command buffer.
pub(crate) type Deferred = Box<dyn FnOnce(&ash::Device, vk::CommandBuffer) + Send>;

/// What [`Context::batched`] collects: commands, and the staging buffers they read.
#[derive(Default)]
pub(super) struct Batch {
    commands: Vec<Deferred>,
    staging: Vec<crate::vk::Buffer>,
}

impl Context {
    /// Runs `f` (object creation) with every upload and fill it makes deferred, then records
    /// them all into one command buffer and submits it once (a barrier from the transfers to
    /// every later command, then a wait): creating a `Renderer`, a `ViewPass` or a `WaterSim`
    /// is one submit (docs/integration.md). Nested calls join the outer batch. When `f` fails,
    /// nothing is submitted and the staging buffers are freed.
    pub fn batched<R>(&self, f: impl FnOnce() -> Result<R>) -> Result<R> {
        let lock = || self.batch.lock().map_err(|_| Error::Unsupported("batch lock poisoned".into()));
        {
            let mut b = lock()?;
            if b.is_some() {
                drop(b);
                return f();
            }
            *b = Some(Batch::default());
        }
        let r = f();
        let batch = lock()?.take().unwrap_or_default();
        let submitted = match (&r, batch.commands.is_empty()) {
            (Ok(_), false) => self.submit_and_wait(|cmd| {
                for (i, c) in batch.commands.into_iter().enumerate() {
                    if i > 0 {
                        // Two uploads may write the same range (a level table, then its origin).
                        crate::vk::barrier::transfer_to_transfer(self, cmd);
                    }
                    c(&self.device, cmd);
                }
                crate::vk::barrier::transfer_to_all(self, cmd);
                Ok(())
            }),
            _ => Ok(()),
        };
        batch.staging.into_iter().for_each(|b| b.destroy(self));
        submitted?;
        r
    }

    /// Defers `command` (and keeps `staging` alive until it ran) when a [`Context::batched`]
    /// is collecting (`None`); otherwise gives both back for an immediate submit.
    pub(crate) fn defer(
        &self,
        command: Deferred,
        staging: Option<crate::vk::Buffer>,
    ) -> Option<(Deferred, Option<crate::vk::Buffer>)> {
        match self.batch.lock() {
            Ok(mut g) => match g.as_mut() {
                Some(b) => {
                    b.commands.push(command);
                    b.staging.extend(staging);
                    None
                }
                None => Some((command, staging)),
            },
            Err(_) => Some((command, staging)),
        }
    }

    /// Records commands with `f` into a fresh primary command buffer, submits it to the queue
    /// and waits for completion. For headless use and uploads; engines record into their own
    /// command buffers instead. The queue must not be used by another thread meanwhile.
    pub fn submit_and_wait<R>(&self, f: impl FnOnce(vk::CommandBuffer) -> Result<R>) -> Result<R> {
        let mut guard = self.submit.lock().map_err(|_| Error::Unsupported("submit lock poisoned".into()))?;
        if guard.is_none() {
            let pool_info = vk::CommandPoolCreateInfo::default()
                .queue_family_index(self.queue_family)
                .flags(vk::CommandPoolCreateFlags::TRANSIENT | vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
            let pool = unsafe { self.device.create_command_pool(&pool_info, None) }.vk("vkCreateCommandPool")?;
            let fence = match unsafe { self.device.create_fence(&vk::FenceCreateInfo::default(), None) } {
                Ok(f) => f,
                Err(e) => {
                    unsafe { self.device.destroy_command_pool(pool, None) };
                    return Err(Error::Vulkan { call: "vkCreateFence", result: e });
                }
            };
            *guard = Some((pool, fence));
        }
        let (pool, fence) = guard.expect("set above");
        let alloc = vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1);
        let cmd = unsafe { self.device.allocate_command_buffers(&alloc) }.vk("vkAllocateCommandBuffers")?[0];
        let run = || -> Result<R> {
            let begin = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            unsafe { self.device.begin_command_buffer(cmd, &begin) }.vk("vkBeginCommandBuffer")?;
            let r = f(cmd)?;
            unsafe { self.device.end_command_buffer(cmd) }.vk("vkEndCommandBuffer")?;
            let cbi = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cbi)];
            unsafe { self.device.reset_fences(&[fence]) }.vk("vkResetFences")?;
            self.submits.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            unsafe { self.device.queue_submit2(self.queue, &submit, fence) }.vk("vkQueueSubmit2")?;
            unsafe { self.device.wait_for_fences(&[fence], true, u64::MAX) }.vk("vkWaitForFences")?;
            Ok(r)
        };
        let result = run();
        unsafe { self.device.free_command_buffers(pool, &[cmd]) };
        result
    }
}
