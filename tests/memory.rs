//! The pure GPU-memory estimate (`hfgi::frame::memory`) against what the renderer and the view
//! pass really allocate on the validated test context: the renderer's total equals
//! `Renderer::memory_bytes()` exactly; the view pass's equals `ViewPass::memory_bytes()` where the
//! driver does not pad its images (and is at most it elsewhere); the entries are, name for name,
//! the allocations the allocator holds for each.

mod common;

use std::collections::BTreeMap;
use std::path::Path;

use hfgi::frame::memory::{self, MemoryEstimate, ViewTargets};
use hfgi::frame::view::{ViewOptions, ViewPass};
use hfgi::frame::Renderer;
use hfgi::scene::file::parse_scene;
use hfgi::scene::model::Scene;
use hfgi::vk::Context;

/// A scene from TOML `text` and `--set` overrides.
fn scene_of(text: &str, overrides: &[&str]) -> Scene {
    let o: Vec<String> = overrides.iter().map(|s| s.to_string()).collect();
    parse_scene(text, Path::new("."), "test", &o).unwrap_or_else(|e| panic!("{overrides:?}: {e}"))
}

/// The covered cases: `(label, TOML text, overrides)`. Small fields, some non-square; a small
/// odd camera keeps the view images cheap (the default 960×540 one is in the list once).
fn cases() -> Vec<(&'static str, &'static str, Vec<&'static str>)> {
    let small = ["heightfield.size=[37,50]", "camera.width=97", "camera.height=61"];
    let with = |extra: &[&'static str]| small.iter().chain(extra).copied().collect::<Vec<_>>();
    let glossy = "material.specular=[0.2,0.2,0.2]";
    vec![
        ("direct only", "", with(&[])),
        ("default camera", "", vec!["heightfield.size=[40,24]", "gi.bounces=1"]),
        ("subsample 2, 1 bounce", "", with(&["gi.subsample=2", "gi.bounces=1"])),
        ("subsample 4, 3 bounces", "", with(&["gi.subsample=4", "gi.bounces=3", "heightfield.size=[64,41]"])),
        ("pyramid mode, 1 bounce", "", with(&["gi.pyramid=\"pyramid\"", "gi.bounces=1"])),
        ("pyramid mode, subsample 2", "", with(&["gi.pyramid=\"pyramid\"", "gi.subsample=2", "gi.bounces=3"])),
        ("wrap, 1 bounce", "", with(&["heightfield.wrap=true", "gi.bounces=1"])),
        ("glossy scalar", "", with(&[glossy, "gi.bounces=1", "gi.glossy_pyramid=\"scalar\""])),
        ("glossy vector", "", with(&[glossy, "gi.bounces=1", "gi.glossy_pyramid=\"vector\""])),
        (
            "glossy vector, pyramid, n=2",
            "",
            with(&[glossy, "gi.bounces=3", "gi.glossy_pyramid=\"vector\"", "gi.pyramid=\"pyramid\"", "gi.sh_order=2"]),
        ),
        ("vector asked, no specular", "", with(&["gi.bounces=1", "gi.glossy_pyramid=\"vector\""])),
        ("black surface", "", with(&["gi.bounces=1", "material.albedo=[0,0,0]"])),
        ("draft", "", with(&["gi.quality=\"draft\"", "gi.bounces=1"])),
        ("default", "", with(&["gi.quality=\"default\"", "gi.bounces=1"])),
        ("high", "", with(&["gi.quality=\"high\"", "gi.bounces=1", "heightfield.size=[33,20]"])),
        ("paper", "", with(&["gi.quality=\"paper\"", "gi.bounces=1"])),
        ("no key light", "", with(&["key_light=[]", "gi.bounces=1"])),
        ("no environment", "[[key_light]]\n", with(&["gi.bounces=1"])),
        ("unlit", "key_light = []\n", with(&["gi.bounces=1"])),
        ("sh order 2", "", with(&["gi.sh_order=2", "gi.bounces=1"])),
        ("sh order 6", "", with(&["gi.sh_order=6", "gi.bounces=1", "heightfield.size=[20,31]"])),
        ("sweep, 1 bounce", "", with(&["gi.visibility=\"sweep\"", "gi.bounces=1"])),
        ("sweep, subsample 4", "", with(&["gi.visibility=\"sweep\"", "gi.subsample=4"])),
        ("sweep, no environment", "[[key_light]]\n", with(&["gi.visibility=\"sweep\""])),
        (
            "local lights only, 1 bounce",
            "[[local_light]]\nposition = [10.0, 12.0, 5.0]\n[[local_light]]\nposition = [30.0, 20.0, 8.0]\n",
            with(&["gi.bounces=1", "gi.local_light_azimuths=5"]),
        ),
        (
            "spheres, log_field, 1 bounce",
            "[[sphere]]\ncenter = [10.0, 12.0, 5.0]\nradius = 3.0\n[[sphere]]\ncenter = [30.0, 20.0, 8.0]\nradius = 2.0\n",
            with(&["gi.bounces=1", "gi.blocker_shading=\"log_field\"", "environment.preset=\"sky\""]),
        ),
        (
            "spheres, primal",
            "[[sphere]]\ncenter = [10.0, 12.0, 5.0]\nradius = 3.0\n",
            with(&["gi.blocker_shading=\"primal\"", "gi.sh_order=6"]),
        ),
        ("f16, subsample 4, 3 bounces", "", with(&["gi.storage=\"f16\"", "gi.subsample=4", "gi.bounces=3"])),
        // The later bounces' own azimuth set: more samples and fold matrices.
        ("later bounces, 8 azimuths", "", with(&["gi.bounces=2", "gi.azimuths_later=8"])),
        ("f16, sh order 3 (odd n²)", "", with(&["gi.storage=\"f16\"", "gi.sh_order=3", "gi.bounces=1"])),
        // U stored to band 1 (4 coefficients per channel) with order-5 V.
        ("exact lobe, n=5, 2 bounces", "", with(&["gi.diffuse_lobe=\"exact\"", "gi.sh_order=5", "gi.bounces=2"])),
        (
            "f16, spheres, log_field",
            "[[sphere]]\ncenter = [10.0, 12.0, 5.0]\nradius = 3.0\n",
            with(&["gi.storage=\"f16\"", "gi.bounces=1", "gi.blocker_shading=\"log_field\"", "environment.preset=\"sky\""]),
        ),
        (
            "spheres, log_brdf, matched log-ZH",
            "[[sphere]]\ncenter = [10.0, 12.0, 5.0]\nradius = 3.0\n",
            with(&["gi.blocker_shading=\"log_brdf\"", "gi.blocker_log_cap=\"matched\"", "environment.preset=\"sky\""]),
        ),
    ]
}

/// The live allocations of `ctx`'s allocator: the sizes under each name (the allocator's
/// chunk sizes, which may include alignment; only the names are compared).
fn live(ctx: &Context) -> BTreeMap<String, Vec<u64>> {
    let report = ctx.allocator().lock().unwrap().generate_report();
    let mut out: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    for a in report.allocations {
        out.entry(a.name).or_default().push(a.size);
    }
    out
}

/// What `make` allocates and keeps: the allocations under names that `ctx` did not hold
/// before (the tests use each name once at a time).
fn allocated_by<T>(ctx: &Context, make: impl FnOnce() -> T) -> (T, BTreeMap<String, Vec<u64>>) {
    let before = live(ctx);
    let made = make();
    let mut after = live(ctx);
    after.retain(|name, _| !before.contains_key(name));
    (made, after)
}

/// The estimate's entries by name (a name may repeat).
fn by_name(e: &MemoryEstimate) -> BTreeMap<String, Vec<u64>> {
    let mut out: BTreeMap<String, Vec<u64>> = BTreeMap::new();
    for (n, b) in &e.buffers {
        out.entry(n.clone()).or_default().push(*b);
    }
    out
}

fn names(m: &BTreeMap<String, Vec<u64>>) -> Vec<(&String, usize)> {
    m.iter().map(|(n, v)| (n, v.len())).collect()
}

/// Checks one scene: totals and names of the renderer and of the view pass.
fn check(ctx: &Context, label: &str, scene: &Scene) {
    let est = memory::renderer(scene).unwrap_or_else(|e| panic!("{label}: {e}"));
    assert!(by_name(&est).values().all(|v| v.len() == 1), "{label}: duplicate names in {:?}", est.buffers);
    let (renderer, made) = allocated_by(ctx, || Renderer::new(ctx, scene).unwrap_or_else(|e| panic!("{label}: {e}")));
    assert_eq!(est.total(), renderer.memory_bytes(), "{label}: renderer estimate\n{est}");
    assert_eq!(names(&by_name(&est)), names(&made), "{label}: renderer buffer names");
    // The estimate's aliases are the renderer's buffers with no memory of their own.
    let shared = renderer.indirect.as_ref().is_some_and(|i| i.radiance.pyramid.levels_aliased());
    let alias = ("hfgi.radiance.levels".to_string(), "hfgi.pyramid.levels".to_string());
    assert_eq!(est.aliases, if shared { vec![alias] } else { vec![] }, "{label}: aliases");
    let largest = est.largest().unwrap();
    assert!(est.buffers.iter().all(|(_, b)| *b <= largest.1), "{label}: largest {largest:?}");

    let opts = ViewOptions::default();
    let (view, made) = allocated_by(ctx, || {
        ViewPass::for_renderer(ctx, scene, &renderer, &opts).unwrap_or_else(|e| panic!("{label}: {e}"))
    });
    let targets =
        ViewTargets { color_format: view.color_format(), depth_format: view.depth_format(), samples: view.samples() };
    let vest = memory::view_with(scene, &targets).unwrap();
    let vnames = by_name(&vest);
    assert_eq!(names(&vnames), names(&made), "{label}: view names");
    // Images are nominal: at most what the driver asks for (the pass reports the driver's size).
    assert!(vnames["hfgi.view.output"][0] <= view.image().size_bytes(), "{label}: output image");
    // Where the driver does not pad (lavapipe: 4×4-pixel blocks, 64-byte rows), the whole pass,
    // images and index buffer, is exact.
    let (cw, ch) = view.size();
    let unpadded = ctx.info().driver.to_lowercase().contains("llvmpipe") && cw % 16 == 0 && ch % 4 == 0;
    if unpadded {
        assert_eq!(vest.total(), view.memory_bytes(), "{label}: view estimate for {targets:?}\n{vest}");
    }
    assert!(vest.total() <= view.memory_bytes(), "{label}: view estimate for {targets:?}\n{vest}");
    let bound = memory::view(scene, &opts).unwrap();
    assert!(bound.total() >= vest.total(), "{label}: view() {} < view_with() {}", bound.total(), vest.total());
    println!(
        "{label:<28} renderer {:>8} B = memory_bytes ({:>2} buffers); view {cw}×{ch} {:?} ×{}: {:>8} B, \
         memory_bytes {:>8} B (driver padding {}){}",
        est.total(),
        est.buffers.len(),
        targets.color_format,
        targets.samples,
        vest.total(),
        view.memory_bytes(),
        view.memory_bytes() - vest.total(),
        if unpadded { ", checked equal" } else { "" }
    );
    view.destroy(ctx);
    renderer.destroy(ctx);
}

#[test]
fn estimate_equals_what_the_passes_allocate() {
    let g = common::gpu();
    for (label, text, overrides) in cases() {
        check(&g, label, &scene_of(text, &overrides));
    }
    let messages = common::finish(g);
    assert!(messages.is_empty(), "validation messages: {messages:?}");
}

/// The bytes of `V` and `U` from first principles: receivers × n² values (V) or 3 × 9 (U of the
/// default diffuse surface: bands 0–2) of 4 bytes (f32) or 2 bytes with each receiver padded to
/// an even count (f16); the radiance stack halves (rounded up to a whole word), and nothing
/// else changes (the shading planes have their own `gi.shading_storage`).
#[test]
fn f16_storage_halves_v_u_and_the_radiance_stack() {
    let bytes = |storage: &str, n: usize| {
        let e = memory::renderer(&scene_of(
            "",
            &[
                "heightfield.size=[64,48]",
                "gi.bounces=1",
                &format!("gi.sh_order={n}"),
                &format!("gi.storage=\"{storage}\""),
            ],
        ))
        .unwrap();
        let get = |name: &str| e.buffers.iter().find(|(b, _)| b == name).unwrap().1;
        (get("hfgi.visibility.v"), get("hfgi.indirect.u"), get("hfgi.radiance.stack"), e.total())
    };
    let receivers = 64 * 48;
    let sets = 2; // the default scene: environment and one key light
    for n in [3u64, 4] {
        let (v32, u32_, r32, t32) = bytes("f32", n as usize);
        let (v16, u16_, r16, t16) = bytes("f16", n as usize);
        let pad = |x: u64| x.div_ceil(2) * 2;
        assert_eq!(v32, sets * receivers * n * n * 4, "n = {n}");
        // A diffuse surface's U keeps bands 0–2 (rules::scene::u_bands: order 4's band 3 is
        // zeroed by the clamped cosine): 9 coefficients for n = 3 and n = 4.
        let u = 9;
        assert_eq!(u32_, receivers * 3 * u * 4, "n = {n}");
        assert_eq!(v16, sets * receivers * pad(n * n) * 2, "n = {n}");
        assert_eq!(u16_, receivers * pad(3 * u) * 2, "n = {n}");
        assert_eq!(r16, (r32 / 4).div_ceil(2) * 4, "n = {n}: radiance stack");
        assert_eq!(t32 - t16, (v32 - v16) + (u32_ - u16_) + (r32 - r16), "n = {n}: nothing else changes");
    }
}

/// The shading buffer holds an RGB `f32` triple per texel (12 bytes; `gi.shading_storage =
/// "rgbe"`: one RGBE word, 4 bytes), six planes for a glossy
/// surface and three (total, direct, indirect) for a diffuse one, and the renderer reports the
/// same plane count; first principles, not the estimate's own formula.
#[test]
fn shading_planes_are_rgb_and_only_a_glossy_surface_has_the_glossy_ones() {
    let ctx = common::gpu();
    // An f32 RGB triple per texel, or one RGBE word (docs/integration.md).
    let cases = [(None, 3u64), (Some("material.specular=[0.2,0.2,0.2]"), 6)];
    for ((specular, planes), (storage, texel)) in cases.into_iter().flat_map(|c| [(c, ("f32", 12)), (c, ("rgbe", 4))]) {
        let st = format!("gi.shading_storage=\"{storage}\"");
        let mut o = vec!["heightfield.size=[37,50]", "gi.bounces=1", st.as_str()];
        o.extend(specular);
        let scene = scene_of("", &o);
        let e = memory::renderer(&scene).unwrap();
        let bytes = e.buffers.iter().find(|(b, _)| b == "hfgi.shade.output").unwrap().1;
        assert_eq!(bytes, planes * 37 * 50 * texel, "specular {specular:?}, {storage}");
        let r = Renderer::new(&ctx, &scene).unwrap();
        assert_eq!(r.shading_planes() as u64, planes);
        assert_eq!(r.shading_buffer().size, planes * 37 * 50 * texel);
        assert_eq!(r.shading_format().texel_bytes(), texel);
        r.destroy(&ctx);
    }
}

#[test]
fn estimate_follows_the_forced_sample_count() {
    let scene = scene_of("", &["heightfield.size=[37,50]", "camera.width=97", "camera.height=61"]);
    let names = |s: u32| {
        let e = memory::view(&scene, &ViewOptions { samples: Some(s) }).unwrap();
        (e.buffers.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>(), e.total())
    };
    let (one, t1) = names(1);
    let (four, t4) = names(4);
    assert_eq!(one, ["hfgi.view.output", "hfgi.view.depth", "hfgi.view.index"]);
    assert_eq!(four, ["hfgi.view.output", "hfgi.view.depth", "hfgi.view.msaa", "hfgi.view.index"]);
    // Output 16 B/px once; depth 4 B/px and colour 16 B/px per sample; 6 u32 indices per quad of a row.
    let px = 97 * 61;
    assert_eq!(t1, px * (16 + 4) + 36 * 4 * 6);
    assert_eq!(t4, px * (16 + 4 * 4 + 16 * 4) + 36 * 4 * 6);
    assert!(memory::view(&scene, &ViewOptions { samples: Some(3) }).is_err());
}

#[test]
fn estimate_rejects_what_the_renderer_rejects() {
    let scene = scene_of("", &["heightfield.size=[37,50]"]);
    let mut bad = scene.clone();
    bad.gi.subsample = 3;
    assert!(memory::renderer(&bad).is_err());
    let mut bad = scene.clone();
    bad.gi.level_step = 0;
    assert!(memory::renderer(&bad).is_err());
}

/// The figures for issue 12's documentation: a 512² field, default preset, 1 bounce, at each
/// sub-sampling (no device); the default preset's storage is f16, less than f32's.
#[test]
fn estimate_512_by_subsample() {
    for sub in [1u32, 2, 4] {
        let s = format!("gi.subsample={sub}");
        let scene = scene_of("", &["heightfield.size=512", "gi.quality=\"default\"", "gi.bounces=1", s.as_str()]);
        let r = memory::renderer(&scene).unwrap();
        let v = memory::view(&scene, &ViewOptions::default()).unwrap();
        assert!(r.total() > 0 && v.total() > 0);
        // The shading planes (total, direct, indirect): `gi.shading_storage = "auto"` keeps an f32
        // triple per texel at full rate and packs one RGBE word sub-sampled (docs/performance.md §37).
        let out = r.buffers.iter().find(|(b, _)| b == "hfgi.shade.output").unwrap().1;
        assert_eq!(out, 3 * 512 * 512 * if sub == 1 { 12 } else { 4 }, "subsample {sub}");
        // The default preset stores V, U and the radiance stack as halves (docs/performance.md §14).
        let mut f16 = vec!["heightfield.size=512", "gi.quality=\"default\"", "gi.bounces=1", s.as_str()];
        f16.push("gi.storage=\"f16\"");
        let mut f32_ = f16.clone();
        f32_[4] = "gi.storage=\"f32\"";
        assert_eq!(r.total(), memory::renderer(&scene_of("", &f16)).unwrap().total());
        if sub == 1 {
            // The decimated stacks from first principles (docs/pyramid.md): each plane is 512²
            // halved while it keeps its level's texels (k = 4: levels 0-3, 512 … 304 texels,
            // keep 512², 4-7 (256 … 152) 256², 8-11 128², 12-15 64², 16-19 32², 20-22 16²).
            // The radiance stack: levels 0-22, 3 channels of halves; the height stack: levels
            // 0-14 (the scans' ladder), f32.
            let get = |name: &str| r.buffers.iter().find(|(b, _)| b == name).unwrap().1;
            let planes = 4 * 512 * 512 + 4 * 256 * 256 + 4 * 128 * 128 + 4 * 64 * 64 + 4 * 32 * 32 + 3 * 16 * 16;
            assert_eq!(get("hfgi.radiance.stack"), 3 * 2 * planes as u64);
            let planes = 4 * 512 * 512 + 4 * 256 * 256 + 4 * 128 * 128 + 3 * 64 * 64;
            assert_eq!(get("hfgi.pyramid.stack"), 4 * planes as u64);
            // The radiance levels (512², 37 levels, 3 f32 channels) in the height levels buffer
            // after level 0 (docs/pyramid.md, "Shared levels").
            let texels: u64 = (0..37).map(|i| (512.0 * 2f64.powf(-i as f64 / 4.0)).round() as u64).map(|w| w * w).sum();
            assert_eq!(get("hfgi.pyramid.levels"), 4 * 512 * 512 + 3 * 4 * texels);
            // Table 1 of the paper: 76 MB at 1× (issue 12).
            assert!(r.total() <= 76_000_000, "{} B", r.total());
        } else {
            // Sub-sampled, the radiance pyramid starts at the working grid (docs/indirect.md §1):
            // a 512/sub pyramid with k_u = 4 (level i has round(N·2^(−i/4)) texels a side,
            // ⌊4·log2 N⌋ + 1 levels), 3 channels of f32; its stack holds levels 0 to 22 − 4·log2
            // sub (the same ladder, k_u·log2 sub levels fewer), halved planes as above.
            let get = |name: &str| r.buffers.iter().find(|(b, _)| b == name).unwrap().1;
            let n = 512 / sub as u64;
            let count = 4 * n.ilog2() as i32 + 1;
            let texels: u64 =
                (0..count).map(|i| ((n as f64) * 2f64.powf(-i as f64 / 4.0)).round() as u64).map(|w| w * w).sum();
            // Shared levels (docs/pyramid.md): the radiance levels live in the height levels
            // buffer after level 0 (512² f32, 1 MiB, a multiple of 256), which has room for the
            // larger of them and the height pyramid's 36 decimated levels; no buffer of their own.
            let height_chain: u64 =
                (1..37).map(|i| (512.0 * 2f64.powf(-i as f64 / 4.0)).round() as u64).map(|w| 4 * w * w).sum();
            assert_eq!(get("hfgi.pyramid.levels"), 4 * 512 * 512 + height_chain.max(3 * 4 * texels), "subsample {sub}");
            assert!(r.buffers.iter().all(|(b, _)| b != "hfgi.radiance.levels"), "subsample {sub}");
            let stack = 23 - 4 * sub.ilog2() as u64;
            let plane = |i: u64| (n >> (i / 4)).pow(2);
            assert_eq!(get("hfgi.radiance.stack"), 3 * 2 * (0..stack).map(plane).sum::<u64>(), "subsample {sub}");
            if sub == 2 {
                // Table 1 of the paper: 20 MB at 2× (issue 12).
                assert!(r.total() <= 20_000_000, "{} B", r.total());
            }
        }
        assert!(r.total() < memory::renderer(&scene_of("", &f32_)).unwrap().total());
        let largest = r.largest().unwrap();
        println!(
            "512², default, 1 bounce, subsample {sub}: renderer {} B ({:.2} MiB; largest {} {:.2} MiB), view (960×540, ≤ 8 samples) {} B ({:.2} MiB)\n{r}",
            r.total(),
            r.total() as f64 / 1048576.0,
            largest.0,
            largest.1 as f64 / 1048576.0,
            v.total(),
            v.total() as f64 / 1048576.0
        );
    }
}

/// `Buffer::aliasing` (the shared levels, docs/pyramid.md): a buffer bound inside another's
/// memory allocates nothing and reads and writes the owner's bytes at its offset; a range past
/// the owner's end is a typed error naming both buffers. In a renderer with indirect light the
/// scalar radiance pyramid's levels alias the height levels buffer, and the vector pyramid's
/// and pyramid mode's do not.
#[test]
fn an_aliasing_buffer_shares_its_owners_bytes() {
    use hfgi::vk::{memory as vkm, Buffer};
    let g = common::gpu();
    let usage = hfgi::vk::raw::BufferUsageFlags::STORAGE_BUFFER
        | hfgi::vk::raw::BufferUsageFlags::TRANSFER_DST
        | hfgi::vk::raw::BufferUsageFlags::TRANSFER_SRC;
    let gpu_only = gpu_allocator::MemoryLocation::GpuOnly;
    let before = live(&g);
    let owner = Buffer::new(&g, "test.owner", 4096, usage, gpu_only).unwrap();
    let alias = Buffer::aliasing(&g, "test.alias", 1024, usage, &owner, 2048).unwrap();
    let mut after = live(&g);
    after.retain(|n, _| !before.contains_key(n));
    assert_eq!(after.keys().collect::<Vec<_>>(), ["test.owner"], "the alias allocates nothing");
    assert_eq!((owner.owned_bytes(), alias.owned_bytes()), (4096, 0));
    let words: Vec<u32> = (0..256).map(|i| 0x5eed_0000 + i).collect();
    vkm::upload(&g, &alias, 0, bytemuck::cast_slice(&words)).unwrap();
    let seen = vkm::download(&g, &owner, 2048, 1024).unwrap();
    assert_eq!(seen, bytemuck::cast_slice::<u32, u8>(&words), "written through the alias, read through the owner");
    vkm::upload(&g, &owner, 2048 + 4, &[1, 2, 3, 4]).unwrap();
    assert_eq!(vkm::download(&g, &alias, 4, 4).unwrap(), [1, 2, 3, 4], "and the other way");
    let err = Buffer::aliasing(&g, "test.past", 1024, usage, &owner, 3328).err().expect("past the end").to_string();
    assert!(err.contains("test.past") && err.contains("test.owner") && err.contains("4096"), "{err}");
    alias.destroy(&g);
    owner.destroy(&g);

    let shares = |overrides: &[&str]| {
        let scene = scene_of("", overrides);
        let r = Renderer::new(&g, &scene).unwrap();
        let out = r.indirect.as_ref().map(|i| i.radiance.pyramid.levels_aliased());
        // The room after level 0 is reserved exactly when it is used.
        assert_eq!(r.pyramid.levels_room() > 0, out == Some(true), "{overrides:?}");
        r.destroy(&g);
        out
    };
    let small = ["heightfield.size=[37,50]", "gi.bounces=1"];
    assert_eq!(shares(&small), Some(true));
    assert_eq!(shares(&[small[0], small[1], "gi.subsample=2"]), Some(true));
    assert_eq!(shares(&[small[0], small[1], "gi.pyramid=\"pyramid\""]), Some(false));
    let vector = [small[0], small[1], "material.specular=[0.2,0.2,0.2]", "gi.glossy_pyramid=\"vector\""];
    assert_eq!(shares(&vector), Some(false));
    assert_eq!(shares(&[small[0], "gi.bounces=0"]), None);
    // A standalone pyramid reserves no room, so an IndirectPass over it keeps its own levels.
    use hfgi::frame::pyramid::{HeightPyramid, PyramidMode};
    let alone = HeightPyramid::new(&g, 64, 64, (16, 16), 4, PyramidMode::Stack, false).unwrap();
    assert_eq!(alone.levels_room(), 0);
    alone.destroy(&g);
    let messages = common::finish(g);
    assert!(messages.is_empty(), "validation messages: {messages:?}");
}
