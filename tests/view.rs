//! The view image (stage `view.raster`, docs/view.md) against an f64 CPU ray caster of the same
//! mesh (one vertex per sample, two triangles per quad split along (i, j)–(i+1, j+1)), seen
//! through the camera model derived here independently of the pass: basis
//! `forward = normalize(target − position)`, `right = normalize(forward × z)` (× y when looking
//! straight up or down), `up = right × forward`, vertical fov, pixel centres at +0.5, row 0 on
//! top. Everything runs on the validated context of `common::gpu()`.

mod common;

use ash::vk as raw;
use common::gpu;
use glam::DVec3;
use gpu_allocator::MemoryLocation;
use hfgi::error::Error;
use hfgi::frame::view::{ViewInputs, ViewOptions, ViewPass, BACKGROUND, MAX_SAMPLES, STAGE_RASTER};
use hfgi::frame::{Renderer, ShadingFormat};
use hfgi::scene::model::{Camera, Environment, KeyLight, SphereBlocker};
use hfgi::vk::{memory, Buffer, Context, Recorder};

/// Heights and shading uploaded into storage buffers, as the renderer would hold them.
struct Inputs {
    w: usize,
    h: usize,
    heights: Vec<f32>,
    colours: Vec<[f32; 3]>,
    hb: Buffer,
    sb: Buffer,
    /// The texel format of `sb`.
    format: ShadingFormat,
}

impl Inputs {
    fn new(ctx: &Context, w: usize, h: usize, f: impl Fn(usize, usize) -> (f32, [f32; 3])) -> Self {
        Self::new_in(ctx, w, h, ShadingFormat::F32, f)
    }

    /// As [`Inputs::new`], with the shading planes in `format`.
    fn new_in(
        ctx: &Context,
        w: usize,
        h: usize,
        format: ShadingFormat,
        f: impl Fn(usize, usize) -> (f32, [f32; 3]),
    ) -> Self {
        let (heights, colours): (Vec<f32>, Vec<[f32; 3]>) = (0..w * h).map(|k| f(k % w, k / w)).unzip();
        Self::from_data(ctx, w, h, heights, colours, format)
    }

    /// The planes in `format`: plane 0 (total) holds `colours`, followed by a garbage plane that
    /// must not be read (negative in f32; RGBE holds no negatives, so a huge magenta there). The
    /// colours kept are what `format` holds of them, so the reference sees exactly the texels
    /// the vertex shader must decode.
    fn from_data(
        ctx: &Context,
        w: usize,
        h: usize,
        heights: Vec<f32>,
        colours: Vec<[f32; 3]>,
        format: ShadingFormat,
    ) -> Self {
        let usage = raw::BufferUsageFlags::STORAGE_BUFFER | raw::BufferUsageFlags::TRANSFER_DST;
        let hb = Buffer::new(ctx, "test.heights", (w * h * 4) as u64, usage, MemoryLocation::GpuOnly).unwrap();
        memory::upload_f32(ctx, &hb, 0, &heights).unwrap();
        let garbage = match format {
            ShadingFormat::F32 => [-7.0f32; 3],
            ShadingFormat::Rgbe => [9000.0, 0.0, 9000.0],
        };
        let mut planes: Vec<[f32; 3]> = colours.clone();
        planes.extend(std::iter::repeat(garbage).take(w * h));
        let bytes = format.encode(&planes);
        let sb = Buffer::new(ctx, "test.shading", bytes.len() as u64, usage, MemoryLocation::GpuOnly).unwrap();
        memory::upload(ctx, &sb, 0, &bytes).unwrap();
        let colours = format.decode(&format.encode(&colours));
        Self { w, h, heights, colours, hb, sb, format }
    }

    fn range(&self) -> (f32, f32) {
        self.heights.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)))
    }

    fn pass(&self, ctx: &Context, camera: &Camera, samples: Option<u32>) -> hfgi::error::Result<ViewPass> {
        let inputs = ViewInputs {
            heights: &self.hb,
            shading: &self.sb,
            shading_format: self.format,
            height_range: self.range(),
        };
        ViewPass::new(ctx, self.w, self.h, camera, 1.0, &inputs, &ViewOptions { samples })
    }

    fn destroy(self, ctx: &Context) {
        self.hb.destroy(ctx);
        self.sb.destroy(ctx);
    }
}

fn render(ctx: &Context, pass: &ViewPass) -> Vec<[f32; 4]> {
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(ctx, cmd, None);
        pass.record(&mut rec);
        assert_eq!(rec.stages(), [STAGE_RASTER]);
        Ok(())
    })
    .unwrap();
    pass.read_rgba(ctx).unwrap()
}

fn camera(position: [f64; 3], target: [f64; 3], fov_deg: f64, width: u32, height: u32) -> Camera {
    Camera {
        position: DVec3::from_array(position),
        target: DVec3::from_array(target),
        fov_deg,
        width,
        height,
        exposure: 0.0,
    }
}

/// The reference camera (see the file docs).
struct RefCamera {
    eye: DVec3,
    right: DVec3,
    up: DVec3,
    forward: DVec3,
    t: f64,
    w: f64,
    h: f64,
}

impl RefCamera {
    fn new(c: &Camera) -> Self {
        let forward = (c.target - c.position).normalize();
        let mut right = forward.cross(DVec3::Z);
        if right.length() < 1e-9 {
            right = forward.cross(DVec3::Y);
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let t = (c.fov_deg.to_radians() / 2.0).tan();
        Self { eye: c.position, right, up, forward, t, w: c.width as f64, h: c.height as f64 }
    }

    /// Direction through pixel position (x, y) (not normalised).
    fn dir(&self, x: f64, y: f64) -> DVec3 {
        let a = self.w / self.h;
        self.forward + (2.0 * x / self.w - 1.0) * self.t * a * self.right + (1.0 - 2.0 * y / self.h) * self.t * self.up
    }

    /// Pixel position of a world point (None behind the camera).
    fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let d = p - self.eye;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let a = self.w / self.h;
        let x = d.dot(self.right) / (z * self.t * a);
        let y = d.dot(self.up) / (z * self.t);
        Some(((x + 1.0) * 0.5 * self.w, (1.0 - y) * 0.5 * self.h))
    }
}

/// One reference pixel: ray distance and colour of the nearest hit, and how many triangles the
/// ray crosses (more than one: the depth test decides), or None.
type RefPixel = Option<(f64, [f64; 3], usize)>;

/// Ray-casts every pixel centre against every triangle of the mesh (Möller–Trumbore, f64),
/// colour = barycentric interpolation of the vertex colours at the hit (perspective-correct).
fn reference(inp: &Inputs, cam: &Camera) -> Vec<RefPixel> {
    let rc = RefCamera::new(cam);
    let (w, h) = (inp.w, inp.h);
    let vert = |i: usize, j: usize| DVec3::new(i as f64, j as f64, inp.heights[j * w + i] as f64);
    let col = |i: usize, j: usize| inp.colours[j * w + i].map(|c| c as f64);
    let mut tris = Vec::new();
    for j in 0..h - 1 {
        for i in 0..w - 1 {
            tris.push([(i, j), (i + 1, j), (i + 1, j + 1)]);
            tris.push([(i, j), (i + 1, j + 1), (i, j + 1)]);
        }
    }
    let tri_pos: Vec<[DVec3; 3]> = tris.iter().map(|t| t.map(|(i, j)| vert(i, j))).collect();
    let mut out = Vec::with_capacity((cam.width * cam.height) as usize);
    for py in 0..cam.height {
        for px in 0..cam.width {
            let d = rc.dir(px as f64 + 0.5, py as f64 + 0.5).normalize();
            let mut best: Option<(f64, usize, f64, f64)> = None;
            let mut hits = 0;
            for (k, [a, b, c]) in tri_pos.iter().enumerate() {
                let (e1, e2) = (*b - *a, *c - *a);
                let p = d.cross(e2);
                let det = e1.dot(p);
                if det.abs() < 1e-14 {
                    continue;
                }
                let s = rc.eye - *a;
                let u = s.dot(p) / det;
                if !(0.0..=1.0).contains(&u) {
                    continue;
                }
                let q = s.cross(e1);
                let v = d.dot(q) / det;
                if v < 0.0 || u + v > 1.0 {
                    continue;
                }
                let t = e2.dot(q) / det;
                if t > 0.0 {
                    hits += 1;
                    if best.map_or(true, |b| t < b.0) {
                        best = Some((t, k, u, v));
                    }
                }
            }
            out.push(best.map(|(t, k, u, v)| {
                let [c0, c1, c2] = tris[k].map(|(i, j)| col(i, j));
                (t, std::array::from_fn(|ch| (1.0 - u - v) * c0[ch] + u * c1[ch] + v * c2[ch]), hits)
            }));
        }
    }
    out
}

/// Compares the GPU image with the reference on pixels whose 3×3 neighbourhood is all hits
/// with smoothly varying ray distances (no silhouette or depth discontinuity).
fn compare(gpu: &[[f32; 4]], reference: &[RefPixel], cam: &Camera) -> Stats {
    let (w, h) = (cam.width as i64, cam.height as i64);
    let (mut n, mut covered, mut hidden, mut worst, mut worst_at) = (0, 0, 0, 0.0f64, String::new());
    for y in 0..h {
        for x in 0..w {
            let Some((t, c, hits)) = reference[(y * w + x) as usize] else { continue };
            covered += 1;
            let at = |dx: i64, dy: i64| {
                let (nx, ny) = (x + dx, y + dy);
                if nx < 0 || ny < 0 || nx >= w || ny >= h {
                    return None;
                }
                reference[(ny * w + nx) as usize].map(|(t, _, _)| t)
            };
            // Every neighbour hit, and the ray distance varies smoothly through the centre in
            // each of the four directions (second difference ≤ 2% of the distance).
            let clean = [(1, 0), (0, 1), (1, 1), (1, -1)].iter().all(|&(dx, dy)| match (at(-dx, -dy), at(dx, dy)) {
                (Some(a), Some(b)) => (a - 2.0 * t + b).abs() <= 0.02 * t,
                _ => false,
            });
            if !clean {
                continue;
            }
            n += 1;
            hidden += usize::from(hits > 1);
            let g = gpu[(y * w + x) as usize];
            for ch in 0..3 {
                let e = (g[ch] as f64 - c[ch]).abs() / c[ch].abs().max(1e-3);
                if e > worst {
                    worst = e;
                    worst_at = format!("pixel ({x}, {y}) channel {ch}: GPU {} vs reference {}", g[ch], c[ch]);
                }
            }
            assert_eq!(g[3], 1.0, "pixel ({x}, {y}): alpha {} on a covered pixel", g[3]);
        }
    }
    Stats { compared: n, covered, hidden, worst, worst_at }
}

/// What [`compare`] found: pixels compared (interior), covered, compared pixels whose ray
/// crosses hidden geometry behind the visible hit, and the max relative error.
struct Stats {
    compared: usize,
    covered: usize,
    hidden: usize,
    worst: f64,
    worst_at: String,
}

/// A field with a ridge that hides part of the slope behind it, and smooth colour ramps.
fn ridge_inputs(ctx: &Context, w: usize, h: usize) -> Inputs {
    Inputs::new(ctx, w, h, |i, j| {
        let (x, y) = (i as f32, j as f32);
        let ridge = 9.0 * (-((y - 0.45 * h as f32).powi(2)) / 18.0).exp();
        let z = ridge + 1.5 * (x * 0.17).sin() * (y * 0.11).cos() + 0.04 * x;
        let c = [0.2 + x / w as f32, 0.3 + y / h as f32, 0.6 + 0.3 * (0.09 * x + 0.05 * y).sin()];
        (z, c)
    })
}

/// Renders with one sample and checks the interior pixels against the ray caster (relative
/// error ≤ 1e-3) and the background; returns the comparison's numbers.
fn check_against_reference(ctx: &Context, inp: &Inputs, cam: &Camera, what: &str) -> Stats {
    let pass = inp.pass(ctx, cam, Some(1)).unwrap();
    assert_eq!(pass.samples(), 1);
    let img = render(ctx, &pass);
    pass.destroy(ctx);
    let r = reference(inp, cam);
    let st = compare(&img, &r, cam);
    let (n, covered, worst) = (st.compared, st.covered, st.worst);
    let total = (cam.width * cam.height) as usize;
    eprintln!(
        "{what}: {covered}/{total} pixels covered, {n} interior pixels compared ({} with hidden geometry behind), \
         max relative error {worst:.2e}",
        st.hidden
    );
    assert!(covered > total / 5 && n > covered / 2, "{what}: too few pixels compared ({n} of {covered})");
    assert!(worst <= 1e-3, "{what}: GPU vs CPU reference: max relative error {worst:e} > 1e-3 at {}", st.worst_at);
    // With MSAA, interior pixels average samples around the centre: close to the reference.
    let pass = inp.pass(ctx, cam, None).unwrap();
    let msaa = render(ctx, &pass);
    let samples = pass.samples();
    pass.destroy(ctx);
    let ms = compare(&msaa, &r, cam);
    eprintln!("{what}, {samples}× MSAA: max relative error of interior pixels {:.2e}", ms.worst);
    assert!(ms.worst <= 2e-2, "{what}: {samples}× MSAA interior pixels off by {:e} at {}", ms.worst, ms.worst_at);
    // Background wherever the reference misses, except next to a hit (edge rasterisation).
    let (w, h) = (cam.width as i64, cam.height as i64);
    for y in 0..h {
        for x in 0..w {
            let near_hit = (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx >= 0 && ny >= 0 && nx < w && ny < h && r[(ny * w + nx) as usize].is_some()
                })
            });
            if !near_hit {
                assert_eq!(img[(y * w + x) as usize], BACKGROUND, "{what}: pixel ({x}, {y}) should be background");
            }
        }
    }
    st
}

#[test]
fn matches_the_cpu_ray_caster_with_one_sample() {
    let ctx = gpu();
    let inp = ridge_inputs(&ctx, 64, 48);
    // Oblique, from the south-west and low enough for the ridge to hide part of the far slope.
    let oblique = camera([-4.0, -12.0, 16.0], [32.0, 26.0, 2.0], 50.0, 96, 64);
    let st = check_against_reference(&ctx, &inp, &oblique, "oblique camera");
    assert!(st.hidden > 100, "the ridge should hide geometry behind it (depth test exercised)");
    // From the east, looking west (the field's x axis runs right to left in the image).
    let east = camera([78.0, 22.0, 16.0], [30.0, 24.0, 3.0], 50.0, 80, 72);
    check_against_reference(&ctx, &inp, &east, "camera from the east");
    inp.destroy(&ctx);
}

/// Shading planes in RGBE (`gi.shading_storage = "rgbe"`): the vertex shader's decoding
/// (`hfgi_plane.glsl`) against the host's encoding and decoding (`ShadingFormat`). Colours
/// spanning 2⁻⁴ … 2⁴ exercise the shared exponent.
#[test]
fn packed_shading_planes_are_decoded_as_the_host_decodes_them() {
    let ctx = gpu();
    let inp = Inputs::new_in(&ctx, 64, 48, ShadingFormat::Rgbe, |i, j| {
        let (x, y) = (i as f32, j as f32);
        let z = 6.0 * (-((y - 20.0).powi(2)) / 30.0).exp() + 0.05 * x;
        let scale = 2f32.powf(8.0 * x / 64.0 - 4.0);
        (z, [scale * (0.3 + y / 48.0), scale * 0.71, scale * (0.9 - 0.4 * y / 48.0)])
    });
    let oblique = camera([-4.0, -12.0, 16.0], [32.0, 26.0, 2.0], 50.0, 96, 64);
    check_against_reference(&ctx, &inp, &oblique, "RGBE shading planes");
    inp.destroy(&ctx);
}

#[test]
fn camera_inside_the_field_looking_straight_down() {
    let ctx = gpu();
    // Heights 0..~10: the camera at z = 6 is inside the field's bounding box.
    let inp = ridge_inputs(&ctx, 48, 48);
    let (lo, hi) = inp.range();
    let cam = camera([24.0, 10.0, 6.0], [24.0, 10.0, -1.0], 70.0, 64, 64);
    assert!(cam.position.z > lo as f64 && cam.position.z < hi as f64);
    check_against_reference(&ctx, &inp, &cam, "straight down from inside the bounding box");
    inp.destroy(&ctx);
}

/// Signed distance (pixels, positive inside) from `p` to the convex polygon `poly`
/// (counter-clockwise or clockwise).
fn inside_distance(poly: &[(f64, f64)], p: (f64, f64)) -> f64 {
    let area: f64 = (0..poly.len())
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            a.0 * b.1 - a.1 * b.0
        })
        .sum();
    let sign = area.signum();
    (0..poly.len())
        .map(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            let (ex, ey) = (b.0 - a.0, b.1 - a.1);
            sign * (ex * (p.1 - a.1) - ey * (p.0 - a.0)) / (ex * ex + ey * ey).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn flat_field_with_constant_shading_covers_the_projected_rectangle() {
    let ctx = gpu();
    let (w, h) = (40, 30);
    let colour = [0.25f32, 0.5, 1.5];
    let inp = Inputs::new(&ctx, w, h, |_, _| (2.0, colour));
    let cam = camera([-12.0, -20.0, 25.0], [20.0, 14.0, 2.0], 40.0, 96, 64);
    let rc = RefCamera::new(&cam);
    let corners: Vec<(f64, f64)> =
        [(0.0, 0.0), ((w - 1) as f64, 0.0), ((w - 1) as f64, (h - 1) as f64), (0.0, (h - 1) as f64)]
            .iter()
            .map(|&(x, y)| rc.project(DVec3::new(x, y, 2.0)).expect("corner in front of the camera"))
            .collect();
    eprintln!("projected corners (pixels): {corners:.2?}");
    for samples in [Some(1), None] {
        let pass = inp.pass(&ctx, &cam, samples).unwrap();
        let img = render(&ctx, &pass);
        let s = pass.samples();
        pass.destroy(&ctx);
        let (mut inside, mut outside, mut edge) = (0, 0, 0);
        for y in 0..cam.height as usize {
            for x in 0..cam.width as usize {
                let p = img[y * cam.width as usize + x];
                let d = inside_distance(&corners, (x as f64 + 0.5, y as f64 + 0.5));
                if d > 0.75 {
                    inside += 1;
                    // Barycentric weights sum to 1 only up to f32 rounding.
                    let ok = (0..3).all(|c| (p[c] - colour[c]).abs() <= 1e-6 * colour[c]) && p[3] == 1.0;
                    assert!(ok, "{s}×: pixel ({x}, {y}) inside the rectangle: {p:?}, expected {colour:?}");
                } else if d < -0.75 {
                    outside += 1;
                    assert_eq!(p, BACKGROUND, "{s}×: pixel ({x}, {y}) outside the rectangle");
                } else {
                    // Partly covered: the resolve averages the colour with the background.
                    edge += 1;
                    assert!((0.0..=1.0).contains(&p[3]), "{s}×: alpha {} at ({x}, {y})", p[3]);
                    for c in 0..3 {
                        let ok = (p[c] - colour[c] * p[3]).abs() <= 2e-6 * colour[c];
                        assert!(ok, "{s}×: edge pixel ({x}, {y}) = {p:?}");
                    }
                }
            }
        }
        eprintln!("{s}× MSAA: {inside} pixels inside, {outside} outside, {edge} on the edge");
        assert!(inside > 1000 && outside > 1000, "the rectangle should fill part of the image");
    }
    inp.destroy(&ctx);
}

#[test]
fn msaa_count_is_the_highest_supported_up_to_8() {
    let ctx = gpu();
    let limits = unsafe { ctx.instance().get_physical_device_properties(ctx.physical_device()) }.limits;
    let fb = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
    let inp = Inputs::new(&ctx, 8, 8, |i, j| ((i + j) as f32 * 0.1, [1.0; 3]));
    let cam = camera([-5.0, -5.0, 8.0], [4.0, 4.0, 0.0], 45.0, 32, 24);
    let pass = inp.pass(&ctx, &cam, None).unwrap();
    let s = pass.samples();
    eprintln!(
        "device '{}': view MSAA {}× ({:?} + {:?}; supported {:?}; framebuffer colour & depth counts {:?})",
        ctx.info().name,
        s,
        pass.color_format(),
        pass.depth_format(),
        pass.supported_samples(),
        fb
    );
    assert!(s.is_power_of_two() && s <= MAX_SAMPLES);
    assert!(fb.as_raw() & s != 0, "{s} samples not in framebuffer counts {fb:?}");
    let best = pass.supported_samples().into_iter().filter(|&c| c <= MAX_SAMPLES).max().unwrap();
    assert_eq!(s, best);
    let img = render(&ctx, &pass);
    assert!(img.iter().all(|p| p.iter().all(|c| c.is_finite())));
    pass.destroy(&ctx);
    // A forced count that no device supports is an error, not a panic.
    for bad in [3, 64] {
        match inp.pass(&ctx, &cam, Some(bad)) {
            Err(Error::InvalidParameter { name, .. }) => assert!(name.contains("sample"), "{name}"),
            Err(e) => panic!("forced {bad} samples: unexpected error {e}"),
            Ok(_) => panic!("forced {bad} samples accepted"),
        }
    }
    inp.destroy(&ctx);
}

#[test]
fn bad_inputs_are_errors() {
    let ctx = gpu();
    let inp = Inputs::new(&ctx, 8, 8, |_, _| (0.0, [1.0; 3]));
    let ok = camera([-5.0, -5.0, 8.0], [4.0, 4.0, 0.0], 45.0, 32, 24);
    let mut same = ok.clone();
    same.target = same.position;
    let mut huge = ok.clone();
    huge.width = ctx.info().max_image_dimension_2d + 1;
    let mut zero = ok.clone();
    zero.height = 0;
    let mut nan = ok.clone();
    nan.position.x = f64::NAN;
    let mut fov = ok.clone();
    fov.fov_deg = 180.0;
    for (what, cam) in
        [("target = position", same), ("too wide", huge), ("zero height", zero), ("NaN", nan), ("fov", fov)]
    {
        let r = inp.pass(&ctx, &cam, None);
        assert!(matches!(r, Err(Error::InvalidParameter { .. })), "{what}: {:?}", r.err());
    }
    // Buffers smaller than the field.
    let small =
        ViewInputs { heights: &inp.hb, shading: &inp.sb, shading_format: ShadingFormat::F32, height_range: (0.0, 0.0) };
    let r = ViewPass::new(&ctx, 16, 16, &ok, 1.0, &small, &ViewOptions::default());
    assert!(matches!(r, Err(Error::InvalidParameter { .. })), "{:?}", r.err());
    let r = ViewPass::new(&ctx, 1, 8, &ok, 1.0, &small, &ViewOptions::default());
    assert!(matches!(r, Err(Error::InvalidParameter { .. })), "{:?}", r.err());
    // Reading before any frame was recorded.
    let pass = inp.pass(&ctx, &ok, None).unwrap();
    assert!(pass.read_hdr(&ctx).is_err());
    pass.destroy(&ctx);
    inp.destroy(&ctx);
}

#[test]
fn frames_reuse_the_pipeline_and_camera_moves_take_effect() {
    let ctx = gpu();
    let inp = ridge_inputs(&ctx, 32, 32);
    let cam = camera([-10.0, -10.0, 25.0], [16.0, 16.0, 2.0], 45.0, 48, 32);
    let before = ctx.pipelines_created();
    let mut pass = inp.pass(&ctx, &cam, None).unwrap();
    assert_eq!(ctx.pipelines_created(), before + 1, "one graphics pipeline per pass");
    let a = render(&ctx, &pass);
    let b = render(&ctx, &pass);
    assert_eq!(a, b, "the same frame twice gives the same image");
    let mut moved = cam.clone();
    moved.position = DVec3::new(50.0, -10.0, 25.0);
    pass.set_camera(&moved).unwrap();
    let c = render(&ctx, &pass);
    assert_ne!(a, c);
    let mut resized = cam.clone();
    resized.width = 64;
    assert!(pass.set_camera(&resized).is_err());
    pass.set_height_range(-50.0, 50.0).unwrap();
    let _ = render(&ctx, &pass);
    assert_eq!(ctx.pipelines_created(), before + 1, "frames and camera moves create no pipelines");
    pass.destroy(&ctx);
    inp.destroy(&ctx);
}

#[test]
fn renderer_then_view_in_one_command_buffer() {
    let ctx = gpu();
    let field = common::rough_field(40, 32, 3);
    let mut scene = common::scenes::scene(field);
    scene.gi.azimuths = 8;
    scene.camera.width = 96;
    scene.camera.height = 64;
    let mut renderer = Renderer::new(&ctx, &scene).unwrap();
    let view = ViewPass::for_renderer(&ctx, &scene, &renderer, &ViewOptions { samples: Some(1) }).unwrap();
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, None);
        renderer.record(&mut rec);
        view.record(&mut rec);
        assert_eq!(rec.stages().last().map(String::as_str), Some(STAGE_RASTER));
        Ok(())
    })
    .unwrap();
    let img = view.read_rgba(&ctx).unwrap();
    let layers = renderer.read_layers(&ctx).unwrap();
    view.destroy(&ctx);
    renderer.destroy(&ctx);
    assert!(img.iter().all(|p| p.iter().all(|c| c.is_finite() && *c >= 0.0)));
    // The same mesh and colours on the CPU: the pass reads the renderer's buffers correctly.
    let inp = Inputs::from_data(&ctx, 40, 32, scene.field.data().to_vec(), layers.total.clone(), ShadingFormat::F32);
    let r = reference(&inp, &scene.camera);
    let Stats { compared: n, covered, worst, .. } = compare(&img, &r, &scene.camera);
    eprintln!("renderer's shading texture: {n} of {covered} covered pixels compared, max relative error {worst:.2e}");
    assert!(n > covered / 3 && worst <= 1e-3, "{n} pixels, max relative error {worst:e}");
    inp.destroy(&ctx);
}

#[test]
fn camera_helpers_agree_with_the_reference_model() {
    let cam = camera([-20.0, -24.0, 22.0], [32.0, 26.0, 2.0], 45.0, 96, 64);
    let m = hfgi::frame::view::CameraModel::new(&cam, 64, 48, 1.0, -1.0, 11.0).unwrap();
    let rc = RefCamera::new(&cam);
    for (x, y) in [(0.5, 0.5), (48.0, 32.0), (95.5, 10.25)] {
        let (_, d) = m.ray(x, y);
        assert!((d - rc.dir(x, y).normalize()).length() < 1e-12);
    }
    // The clip-space matrix projects like the reference and keeps depth in (0, 1), reversed.
    let vp = m.view_projection();
    for p in [DVec3::new(3.0, 5.0, 1.0), DVec3::new(60.0, 40.0, 10.0), DVec3::new(30.0, 2.0, -1.0)] {
        let c = vp * p.extend(1.0);
        let (px, py) = ((c.x / c.w + 1.0) * 48.0, (c.y / c.w + 1.0) * 32.0);
        let (rx, ry) = rc.project(p).unwrap();
        assert!((px - rx).abs() < 1e-9 && (py - ry).abs() < 1e-9, "{p}: ({px}, {py}) vs ({rx}, {ry})");
        let z = c.z / c.w;
        assert!(z > 0.0 && z < 1.0, "{p}: depth {z}");
    }
    let near = vp * (m.eye + m.forward * m.near).extend(1.0);
    let far = vp * (m.eye + m.forward * m.far).extend(1.0);
    assert!((near.z / near.w - 1.0).abs() < 1e-9 && (far.z / far.w).abs() < 1e-9);
    // Straight down: image up is +y, right is +x.
    let down = camera([5.0, 5.0, 10.0], [5.0, 5.0, 0.0], 45.0, 10, 10);
    let m = hfgi::frame::view::CameraModel::new(&down, 8, 8, 1.0, 0.0, 1.0).unwrap();
    assert!((m.up - DVec3::Y).length() < 1e-12 && (m.right - DVec3::X).length() < 1e-12);
}

#[test]
fn looking_away_from_the_field_gives_the_background() {
    let ctx = gpu();
    let inp = ridge_inputs(&ctx, 16, 16);
    let cam = camera([-5.0, -5.0, 5.0], [-20.0, -20.0, 5.0], 60.0, 32, 24);
    let pass = inp.pass(&ctx, &cam, None).unwrap();
    let img = render(&ctx, &pass);
    assert!(img.iter().all(|p| *p == BACKGROUND));
    assert_eq!(pass.read_hdr(&ctx).unwrap().len(), 32 * 24);
    pass.destroy(&ctx);
    inp.destroy(&ctx);
}

/// Irradiance at the normal +z, computed here from the formula of docs/view.md §6: the first 9
/// SH coefficients with the clamped-cosine factors (only `y_0^0`, `y_1^0` and `y_2^0` are
/// non-zero at +z) plus `L·2π(1 − cos α)·max(d_z, 0)` per key light.
fn irradiance_up(env: &Environment, keys: &[KeyLight]) -> [f64; 3] {
    use std::f64::consts::PI;
    let c = |k: usize| env.sh.get(k).copied().unwrap_or([0.0; 3]);
    let (y00, y10, y20) = (0.5 / PI.sqrt(), (3.0 / (4.0 * PI)).sqrt(), 2.0 * 0.25 * (5.0 / PI).sqrt());
    let mut e: [f64; 3] =
        std::array::from_fn(|i| PI * y00 * c(0)[i] + 2.0 * PI / 3.0 * y10 * c(2)[i] + PI / 4.0 * y20 * c(6)[i]);
    for l in keys {
        let f = 2.0 * PI * (1.0 - l.angular_radius.cos()) * l.direction.z.max(0.0);
        (0..3).for_each(|i| e[i] += l.radiance[i] * f);
    }
    e
}

fn sphere_colour_up(s: &SphereBlocker, env: &Environment, keys: &[KeyLight]) -> [f64; 3] {
    let e = irradiance_up(env, keys);
    std::array::from_fn(|i| s.albedo[i] / std::f64::consts::PI * e[i])
}

fn assert_close(got: [f32; 4], want: [f64; 3], what: &str) {
    let worst = (0..3).map(|i| (f64::from(got[i]) - want[i]).abs() / want[i].abs()).fold(0.0, f64::max);
    eprintln!("{what}: GPU {:?}, expected {want:?}, max relative error {worst:.2e}", &got[..3]);
    assert!(worst <= 1e-3 && got[3] == 1.0, "{what}: GPU {got:?}, expected {want:?}");
}

#[test]
fn spheres_are_drawn_lit_and_depth_tested_with_the_field() {
    let ctx = gpu();
    // A flat field at z = 0 with a shading gradient; the camera looks straight down at its
    // centre; an odd image size puts a pixel centre exactly on the image centre.
    let n = 33;
    let inp = Inputs::new(&ctx, n, n, |i, j| (0.0, [0.2 + 0.01 * i as f32, 0.3 + 0.005 * j as f32, 0.4]));
    let (size, fov) = (65u32, 40.0);
    let cam = camera([16.0, 16.0, 40.0], [16.0, 16.0, 0.0], fov, size, size);
    let before = ctx.pipelines_created();
    let mut pass = inp.pass(&ctx, &cam, Some(1)).unwrap();
    let plain = render(&ctx, &pass);
    let env = common::scenes::sky(4);
    let keys = vec![common::scenes::key_light(60.0, 30.0, 5.0, 4.0), common::scenes::key_light(-20.0, 0.0, 3.0, 9.0)];
    pass.set_sphere_lighting(&ctx, &env, &keys).unwrap();
    assert_eq!(ctx.pipelines_created(), before + 1, "lighting alone creates nothing");
    let sphere = SphereBlocker { center: DVec3::new(16.0, 16.0, 5.0), radius: 3.0, albedo: [0.8, 0.5, 0.3] };
    let dark = SphereBlocker { center: DVec3::new(0.0, 0.0, -1e10), radius: 1.0, albedo: [0.0; 3] };
    pass.set_spheres(&ctx, &[sphere.clone(), dark.clone()]).unwrap();
    assert_eq!(ctx.pipelines_created(), before + 2, "the sphere pipeline");
    assert_eq!(pass.sphere_count(), 1, "the dark slot is skipped");
    let img = render(&ctx, &pass);
    let w = size as usize;
    let centre = img[(w / 2) * w + w / 2];
    // The image centre sees the sphere's top, normal +z.
    assert_close(centre, sphere_colour_up(&sphere, &env, &keys), "sphere top");
    // Away from the sphere's disc (projected radius + 2 px) the field is as without it.
    let dist = 40.0 - 5.0;
    let disc = (sphere.radius / dist).asin().tan() / (fov / 2.0f64).to_radians().tan() * f64::from(size) / 2.0 + 2.0;
    let mut same = 0;
    for (k, (a, b)) in img.iter().zip(&plain).enumerate() {
        let (x, y) = ((k % w) as f64 + 0.5 - f64::from(size) / 2.0, (k / w) as f64 + 0.5 - f64::from(size) / 2.0);
        if (x * x + y * y).sqrt() > disc {
            assert_eq!(a, b, "pixel ({}, {}) outside the sphere changed", k % w, k / w);
            same += 1;
        } else if (x * x + y * y).sqrt() < disc - 4.0 {
            assert_ne!(a, b, "pixel ({}, {}) inside the sphere's disc shows the field", k % w, k / w);
        }
    }
    eprintln!("{same} pixels outside the sphere's disc (radius {disc:.1} px) equal the field without spheres");
    assert!(same > w * w / 2);
    // A corner pixel far from the sphere: the field's shading as before.
    assert_eq!(img[2 * w + 2], plain[2 * w + 2]);
    assert_eq!(img[2 * w + 2][3], 1.0);
    // Below the field the sphere is hidden by it (depth test): the image is the field's.
    let below = SphereBlocker { center: DVec3::new(16.0, 16.0, -6.0), ..sphere.clone() };
    pass.set_spheres(&ctx, &[below]).unwrap();
    assert_eq!(render(&ctx, &pass), plain, "a sphere under the field is hidden");
    // Half sunk into the field: its top is still drawn, the field hides the rest.
    let sunk = SphereBlocker { center: DVec3::new(16.0, 16.0, 0.0), ..sphere.clone() };
    pass.set_spheres(&ctx, std::slice::from_ref(&sunk)).unwrap();
    assert_close(render(&ctx, &pass)[(w / 2) * w + w / 2], sphere_colour_up(&sunk, &env, &keys), "sunk sphere top");
    // A big sphere far below the field (behind it, hidden) widens the far plane a million
    // times, which would push the near plane (1e-5 · far) past the field: the field is not
    // clipped and looks the same.
    let far = SphereBlocker { center: DVec3::new(16.0, 16.0, -3e7), radius: 1e4, ..sphere.clone() };
    pass.set_spheres(&ctx, &[far]).unwrap();
    assert!(pass.camera_model().far > 1e7);
    assert_eq!(render(&ctx, &pass), plain, "a sphere far away does not clip the field");
    // No live spheres: the image is the original bit for bit.
    pass.set_spheres(&ctx, &[dark]).unwrap();
    assert_eq!(pass.sphere_count(), 0);
    assert_eq!(render(&ctx, &pass), plain, "no live spheres: the field alone");
    assert_eq!(ctx.pipelines_created(), before + 2, "sphere moves create no pipelines");
    // More key lights, then more spheres than the objects hold room for: they are recreated
    // (one pipeline each time) and keep what was set.
    pass.set_spheres(&ctx, std::slice::from_ref(&sphere)).unwrap();
    let mut keys3 = keys.clone();
    keys3.push(common::scenes::key_light(80.0, 100.0, 10.0, 2.0));
    pass.set_sphere_lighting(&ctx, &env, &keys3).unwrap();
    assert_eq!((ctx.pipelines_created(), pass.sphere_count()), (before + 3, 1));
    assert_close(render(&ctx, &pass)[(w / 2) * w + w / 2], sphere_colour_up(&sphere, &env, &keys3), "3 key lights");
    let small = SphereBlocker { center: DVec3::new(4.0, 4.0, 2.0), radius: 1.0, albedo: [0.5; 3] };
    let other = SphereBlocker { center: DVec3::new(28.0, 28.0, 2.0), ..small.clone() };
    pass.set_spheres(&ctx, &[small, sphere.clone(), other]).unwrap();
    assert_eq!((ctx.pipelines_created(), pass.sphere_count()), (before + 4, 3));
    assert_close(render(&ctx, &pass)[(w / 2) * w + w / 2], sphere_colour_up(&sphere, &env, &keys3), "3 spheres");
    pass.destroy(&ctx);
    // With the automatic (MSAA) sample count: the fragment shader runs once per pixel (no
    // sample shading), so the covered centre pixel has the same colour.
    let mut msaa = inp.pass(&ctx, &cam, None).unwrap();
    msaa.set_sphere_lighting(&ctx, &env, &keys).unwrap();
    msaa.set_spheres(&ctx, std::slice::from_ref(&sphere)).unwrap();
    let got = render(&ctx, &msaa)[(w / 2) * w + w / 2];
    let want = sphere_colour_up(&sphere, &env, &keys);
    let worst = (0..3).map(|i| (f64::from(got[i]) - want[i]).abs() / want[i]).fold(0.0, f64::max);
    eprintln!("{} samples: sphere top {:?}, relative error {worst:.2e}", msaa.samples(), &got[..3]);
    assert!(worst <= 1e-3 && got[3] == 1.0, "{got:?} vs {want:?}");
    msaa.destroy(&ctx);
    inp.destroy(&ctx);
}

#[test]
fn for_renderer_draws_the_renderers_spheres() {
    let ctx = gpu();
    let field = common::rough_field(24, 24, 5);
    let mut scene = common::scenes::scene(field);
    scene.gi.azimuths = 8;
    scene.camera = camera([11.5, 11.5, 40.0], [11.5, 11.5, 0.0], 40.0, 33, 33);
    // Without spheres: one pipeline, no sphere objects.
    let renderer = Renderer::new(&ctx, &scene).unwrap();
    let before = ctx.pipelines_created();
    let view = ViewPass::for_renderer(&ctx, &scene, &renderer, &ViewOptions { samples: Some(1) }).unwrap();
    assert_eq!(ctx.pipelines_created(), before + 1);
    assert_eq!(view.sphere_count(), 0);
    let bytes = view.memory_bytes();
    view.destroy(&ctx);
    renderer.destroy(&ctx);
    // With one sphere above the centre.
    let sphere = SphereBlocker { center: DVec3::new(11.5, 11.5, 20.0), radius: 2.0, albedo: [0.3, 0.6, 0.9] };
    scene.spheres = vec![sphere.clone()];
    let mut renderer = Renderer::new(&ctx, &scene).unwrap();
    let before = ctx.pipelines_created();
    let view = ViewPass::for_renderer(&ctx, &scene, &renderer, &ViewOptions { samples: Some(1) }).unwrap();
    assert_eq!(ctx.pipelines_created(), before + 2);
    assert_eq!(view.sphere_count(), 1);
    assert!(view.memory_bytes() > bytes);
    ctx.submit_and_wait(|cmd| {
        let mut rec = Recorder::new(&ctx, cmd, None);
        renderer.record(&mut rec);
        view.record(&mut rec);
        Ok(())
    })
    .unwrap();
    let img = view.read_rgba(&ctx).unwrap();
    assert_close(
        img[16 * 33 + 16],
        sphere_colour_up(&sphere, &scene.environment, &scene.key_lights),
        "renderer's sphere",
    );
    // The field around the sphere's disc (about 4.5 px) is drawn (alpha 1) with the renderer's
    // shading.
    let field_pixel = img[6 * 33 + 16];
    assert!(field_pixel[3] == 1.0 && field_pixel[..3].iter().all(|c| c.is_finite() && *c > 0.0), "{field_pixel:?}");
    assert!(img.iter().all(|p| p.iter().all(|c| c.is_finite())));
    view.destroy(&ctx);
    renderer.destroy(&ctx);
}

/// The height field's cast shadow on a sphere (docs/view.md §6): a sphere beside a wall, lit by
/// one key light behind the wall, black environment, seen from straight above (the centre pixel
/// is the sphere's top, normal +z). The key light's visible fraction is the linear ramp
/// `clamp((e + α − ω_b) / 2α, 0, 1)` of the blocking angle `ω_b` seen from the top point.
#[test]
fn the_field_shadows_the_spheres() {
    use std::f64::consts::PI;
    let ctx = gpu();
    let (n, size, fov) = (33, 65u32, 40.0);
    let env = Environment { sh: Vec::new() };
    // Elevation 30°, azimuth 0 (behind the wall, which runs along y at x ∈ [20, 21]).
    let keys = vec![common::scenes::key_light(30.0, 0.0, 3.0, 5.0)];
    let w = size as usize;
    let top = |offset: f64, wall: Option<f32>, env: &Environment| -> ([f32; 4], SphereBlocker) {
        let base = offset as f32;
        let inp = Inputs::new(&ctx, n, n, |i, _| {
            let z = if (20..=21).contains(&i) { wall.map_or(base, |h| base + h) } else { base };
            (z, [0.5; 3])
        });
        let cam = camera([14.0, 16.0, offset + 40.0], [14.0, 16.0, offset], fov, size, size);
        let mut pass = inp.pass(&ctx, &cam, Some(1)).unwrap();
        pass.set_sphere_lighting(&ctx, env, &keys).unwrap();
        let sphere =
            SphereBlocker { center: DVec3::new(14.0, 16.0, offset + 4.0), radius: 3.0, albedo: [0.8, 0.5, 0.3] };
        pass.set_spheres(&ctx, std::slice::from_ref(&sphere)).unwrap();
        let px = render(&ctx, &pass)[(w / 2) * w + w / 2];
        pass.destroy(&ctx);
        inp.destroy(&ctx);
        (px, sphere)
    };
    for offset in [0.0, 1e6] {
        // No wall: the unshadowed formula (the field is below the top point's horizontal).
        let (open, sphere) = top(offset, None, &env);
        let lit = sphere_colour_up(&sphere, &env, &keys);
        assert_close(open, lit, &format!("offset {offset}: no wall"));
        // A tall wall (height 30, ω_b ≈ 75° > e + α = 33°): the key light is hidden.
        let (hidden, _) = top(offset, Some(30.0), &env);
        let ratio = (0..3).map(|i| f64::from(hidden[i]) / lit[i]).fold(0.0, f64::max);
        eprintln!("offset {offset}: tall wall: GPU {:?}, {ratio:.2e} of the unshadowed colour", &hidden[..3]);
        assert!(ratio < 0.01 && hidden[3] == 1.0, "offset {offset}: {hidden:?} vs unshadowed {lit:?}");
        // A wall whose top edge (6 texels away, 7 + 6·tan 30° high) is seen from the top point
        // at the light's elevation: half the cap is visible. The expected fraction uses the
        // wall height as stored in f32 (offset + h rounded to 1/16 at 1e6).
        let h = 7.0 + 6.0 * (PI / 6.0).tan();
        let stored = f64::from(offset as f32 + h as f32) - offset;
        let wb = ((stored - 7.0) / 6.0).atan();
        let alpha = keys[0].angular_radius;
        let vis = ((PI / 6.0 + alpha - wb) / (2.0 * alpha)).clamp(0.0, 1.0);
        let (half, _) = top(offset, Some(h as f32), &env);
        assert_close(
            half,
            lit.map(|c| c * vis),
            &format!("offset {offset}: wall at the light's elevation (V = {vis:.4})"),
        );
        // A uniform environment of radiance 1 (E = π on the top, no key light through the tall
        // wall): the occlusion factor F = mean over 8 azimuths of 1 / (1 + tan²ω⁺): toward the
        // wall (φ = 0) the slope is (30 − 7)/6, at φ = ±45° the wall is 6√2 texels away, the
        // other 5 azimuths see the flat field below the point's horizontal.
        let (m0, m45) = (23.0 / 6.0, 23.0 / (6.0 * 2f64.sqrt()));
        let f = (5.0 + 1.0 / (1.0 + m0 * m0) + 2.0 / (1.0 + m45 * m45)) / 8.0;
        let (occluded, _) = top(offset, Some(30.0), &common::scenes::uniform(1.0));
        assert_close(occluded, sphere.albedo.map(|a| a * f), &format!("offset {offset}: environment, F = {f:.4}"));
    }
}
