//! Sub-sampling's radiance pyramid on the working grid (docs/indirect.md §1, "Sub-sampled
//! radiance"; docs/performance.md §27): the GPU against the f64 twin, which averages the cells
//! itself, and what the frame leaves in the shading planes.

mod common;

use common::scenes::{rel_l2, scene};
use common::{gpu, record_frame, rough_field};
use hfgi::frame::{Renderer, ShadingLayers};
use hfgi::reference::indirect::render_gi;
use hfgi::scene::model::{Albedo, Scene};
use hfgi::vk::Context;

/// A glossy (scalar pyramid), bright `w × h` field with 3 bounces at sub-sampling `sub`.
fn glossy_scene(w: usize, h: usize, sub: u32, wrap: bool) -> Scene {
    let mut s = scene(rough_field(w, h, 5));
    s.material.albedo = Albedo::Constant([0.8, 0.7, 0.6]);
    s.material.specular = Some([0.3, 0.3, 0.3]);
    s.material.exponent = 8.0;
    (s.gi.azimuths, s.gi.bounces, s.gi.subsample, s.wrap) = (16, 3, sub, wrap);
    s
}

/// Records one frame; the recorded stage names and the layers.
fn frame(ctx: &Context, r: &mut Renderer) -> (Vec<String>, ShadingLayers) {
    let names = record_frame(ctx, r);
    (names, r.read_layers(ctx).unwrap())
}

/// The total plane holds what CONVENTIONS.md exports, direct + indirect + glossy, at every texel
/// (the shade's own sum in f32, so to rounding): the exit radiance a bounce passed to the next
/// through it must not survive the frame.
fn assert_total_is_the_sum(l: &ShadingLayers, what: &str) {
    for (i, t) in l.total.iter().enumerate() {
        for (c, &v) in t.iter().enumerate() {
            let sum = l.direct[i][c] + l.indirect[i][c] + l.glossy[i][c];
            assert!((v - sum).abs() <= 1e-6 * sum.abs().max(1e-6), "{what}: texel {i} total {v} ≠ {sum}");
        }
    }
}

/// GPU = twin (relative L2 ≤ 1e-3 per layer) with the working-grid pyramid: a periodic field
/// that 2 divides, and one that 4 does not (30×22 → 8×6 cells of 3–4 texels); glossy, so
/// bounce 1 gathers the direct glossy plane too; 3 bounces, so bounces 2 and 3 gather from the
/// total plane. Every bounce records `radiance.gather`, level 0 has the working grid's size, and
/// the total plane holds the sum after the frame and after each half of an amortised change.
#[test]
fn sub_sampled_radiance_pyramid_starts_at_the_working_grid() {
    let ctx = gpu();
    for (sub, wrap) in [(2u32, true), (4, false)] {
        let s = glossy_scene(30, 22, sub, wrap);
        let what = format!("subsample {sub}, wrap={wrap}, 30×22, glossy, 3 bounces");
        let mut r = Renderer::new(&ctx, &s).unwrap();
        let (names, g) = frame(&ctx, &mut r);
        let c = render_gi(&s).unwrap();
        for (layer, a, b) in
            [("indirect", &g.indirect, &c.indirect), ("glossy", &g.glossy, &c.glossy), ("total", &g.total, &c.total)]
        {
            let e = rel_l2(a, b);
            eprintln!("{what}: GPU vs twin {layer} {e:.2e}");
            assert!(e <= 1e-3, "{what}: GPU vs twin {layer}: relative L2 {e:e}");
        }
        assert_eq!(names.iter().filter(|n| *n == "radiance.gather").count(), 3, "{what}: {names:?}");
        let cells = 30usize.div_ceil(sub as usize) * 22usize.div_ceil(sub as usize);
        let next = r.debug_buffers(&ctx).unwrap().into_iter().find(|(n, _)| n == "indirect.next").unwrap().1;
        assert_eq!(next.len(), 3 * cells, "{what}: level 0 is the working grid");
        assert_total_is_the_sum(&g, &what);
        // An amortised light change: one frame re-shades the direct light, the next the three
        // bounces (which first depends on the frame's parity).
        r.set_environment(&s.environment.scaled(0.5)).unwrap();
        let mut halves = Vec::new();
        for _ in 0..2 {
            let (names, l) = frame(&ctx, &mut r);
            let has = |stage: &str| names.iter().any(|n| n == stage);
            let half = match (has("shade.direct"), has("indirect.shade")) {
                (true, false) => "direct",
                (false, true) => "indirect",
                _ => panic!("{what}: not one half of an amortised change: {names:?}"),
            };
            assert_total_is_the_sum(&l, &format!("{what}, the {half} half"));
            halves.push(half);
        }
        halves.sort();
        assert_eq!(halves, ["direct", "indirect"], "{what}");
        r.destroy(&ctx);
    }
}
