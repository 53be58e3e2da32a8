//! Proof that the validation net is real: a test-only pass records a deliberately invalid
//! barrier, and the harness sees the layer's error.

mod common;

use ash::vk;
use hfgi::vk::Recorder;

/// A "pass" whose barrier pairs a shader-write access with the copy stage, which
/// synchronization2 forbids (VUID-VkMemoryBarrier2-srcAccessMask-03909 and friends).
fn bad_barrier_pass(rec: &mut Recorder) {
    rec.scope("test.bad_barrier", |ctx, cmd| {
        let b = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::SHADER_STORAGE_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::COMPUTE_SHADER)
            .dst_access_mask(vk::AccessFlags2::SHADER_STORAGE_READ)];
        let dep = vk::DependencyInfo::default().memory_barriers(&b);
        unsafe { ctx.device().cmd_pipeline_barrier2(cmd, &dep) };
    });
}

#[test]
fn a_bad_barrier_is_reported() {
    let ctx = common::gpu();
    assert!(ctx.validation_enabled());
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, None);
        bad_barrier_pass(&mut rec);
        Ok(())
    })
    .unwrap();
    let err = ctx.check_validation().expect_err("the layer must report the bad barrier");
    let text = err.to_string();
    eprintln!("caught as expected: {text}");
    assert!(text.contains("VUID-VkMemoryBarrier2"), "{text}");
    // After check_validation took the messages, the context is clean again.
    assert!(ctx.check_validation().is_ok());
}

#[test]
fn the_harness_fails_a_test_that_leaves_messages() {
    let result = std::thread::spawn(|| {
        let mut ctx = common::gpu();
        ctx.deliberate = true;
        ctx.submit_and_wait(|cmd| {
            let mut rec = Recorder::new(&ctx, cmd, None);
            bad_barrier_pass(&mut rec);
            Ok(())
        })
        .unwrap();
        drop(ctx); // the harness panics here
    })
    .join();
    let payload = result.expect_err("the harness must fail a test with validation messages");
    let msg = payload.downcast_ref::<String>().cloned().unwrap_or_default();
    assert!(msg.contains("validation layer reported"), "{msg}");
}

#[test]
fn leaked_objects_are_reported_at_device_destruction() {
    let ctx = common::gpu();
    let buf = hfgi::vk::Buffer::new(
        &ctx,
        "deliberately leaked",
        256,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        gpu_allocator::MemoryLocation::GpuOnly,
    )
    .unwrap();
    std::mem::forget(buf);
    let messages = common::finish(ctx);
    assert!(!messages.is_empty(), "a leaked VkBuffer must be reported when the device is destroyed");
    eprintln!("leak reported: {}", messages[0]);
}
