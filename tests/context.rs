//! Device choice and embedding: `HFGI_DEVICE`-style filters, and `Context::from_raw` wrapping a
//! host's objects without destroying them.

mod common;

use hfgi::frame::pyramid::{HeightPyramid, PyramidMode};
use hfgi::vk::{Context, ContextOptions, RawHandles, Recorder};

fn run_pyramid(ctx: &Context) -> Vec<f32> {
    let field = common::rough_field(40, 30, 3);
    let pyr = HeightPyramid::new(ctx, 40, 30, (40, 30), 4, PyramidMode::Pyramid, false).unwrap();
    pyr.upload(ctx, &field).unwrap();
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, None);
        pyr.record(&mut rec);
        Ok(())
    })
    .unwrap();
    let top = pyr.read_level(ctx, pyr.layout().count() - 1).unwrap();
    pyr.destroy(ctx);
    top
}

#[test]
fn device_filter_picks_or_explains() {
    let err = Context::headless_with(&ContextOptions {
        validation: Some(false),
        device_filter: Some("no such gpu".into()),
        sync_validation: None,
    })
    .err()
    .expect("a filter matching nothing must fail");
    let msg = err.to_string();
    assert!(msg.contains("no such gpu") && msg.contains("devices present"), "{msg}");
    let name = common::gpu().info().name.clone();
    let word = name.split_whitespace().next().unwrap().to_lowercase();
    let ctx = Context::headless_with(&ContextOptions {
        validation: Some(false),
        device_filter: Some(word.to_uppercase()),
        sync_validation: None,
    })
    .expect("case-insensitive substring of the device name");
    assert_eq!(ctx.info().name, name);
}

#[test]
fn from_raw_borrows_and_never_destroys_host_objects() {
    let host = common::gpu();
    let expected = run_pyramid(&host);
    {
        let wrapped = Context::from_raw(RawHandles {
            entry: host.entry().clone(),
            instance: host.instance().clone(),
            physical_device: host.physical_device(),
            device: host.device().clone(),
            queue: host.queue(),
            queue_family_index: host.queue_family(),
            allocator: host.allocator().clone(),
            debug_utils: host.debug_utils().is_some(),
            enabled: hfgi::vk::EnabledFeatures { synchronization2: true, dynamic_rendering: true },
            pipeline_cache: hfgi::ash::vk::PipelineCache::null(),
        })
        .unwrap();
        assert_eq!(run_pyramid(&wrapped), expected);
    } // the wrapper is dropped here: it must destroy only its own pool and fence
      // The host's device, queue and allocator still work, and the validation layer (checked when
      // `host` drops) saw nothing wrong.
    assert_eq!(run_pyramid(&host), expected);
}
