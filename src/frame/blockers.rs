//! Stage `visibility.blockers` (docs/blockers.md; seed 001 §3–5, Ren et al. 2006): the sphere
//! blockers' visibility at every receiver of the working grid, as SH, from one exponentiation
//! of the sum of their log-SH vectors; with `gi.blocker_shading = "log"` also the
//! environment's combined visibility `exp*(f_hf + Σ f_i)`. `shade.direct` (and each bounce's
//! shading) multiplies the incident radiance by it. f64 twin: [`crate::reference::blockers`].
//!
//! Buffers: `hfgi.blockers.spheres` (2 `vec4` per slot: the centre's high f32 part and the
//! radius, the low part; written at creation and by [`crate::frame::Renderer::set_spheres`]
//! through `inputs.update`), `hfgi.blockers.quad` (the exponentiation's quadrature: per node
//! its weight and the `n²` SH basis values), `hfgi.blockers.consts` (the `K_l^m` table and the
//! optimal-linear `a`, `b` tables of order n, the log-SH diffuse BRDF, the matched log-ZH table), `hfgi.blockers.v` (per receiver `n²` floats,
//! twice with the log mode). Reads the heights (level 0, absolute) and, in log mode, the
//! visibility pass's buffer. After `record`, a compute→compute barrier has been recorded.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::shared::BlockerPush;
use super::visibility::VisibilityPass;
use crate::error::Result;
use crate::math::shexp::{self, SphereQuadrature};
use crate::rules::lighting::SetKind;
use crate::scene::model::{
    BlockerExp, BlockerKeyLights, BlockerLogCap, BlockerShading, Scene, SphereBlocker, LOG_BRDF_EPSILON,
};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

pub const STAGE_BLOCKERS: &str = super::stages::stage_name("visibility.blockers");

pub(crate) const SPHERES_BUFFER: &str = "hfgi.blockers.spheres";
pub(crate) const QUAD_BUFFER: &str = "hfgi.blockers.quad";
pub(crate) const CONSTS_BUFFER: &str = "hfgi.blockers.consts";
pub(crate) const OUTPUT_BUFFER: &str = "hfgi.blockers.v";
pub(crate) const TRIPLE_BUFFER: &str = "hfgi.blockers.triple";

/// How the shading uses the blockers' buffer (specialization constant 3 of
/// `glsl/shade/direct.comp.glsl`): 0 no blockers, 1 `T ⊛ V_s` (`log`, `primal`), 2
/// `log_field` (the environment set's visibility replaced by the pass's second vector), 3
/// `log_brdf` (as 2, and the environment's diffuse light from the third vector, a transfer).
pub(crate) fn shading_mode(scene: &Scene) -> u32 {
    if scene.spheres.is_empty() {
        0
    } else {
        1 + log_mode(scene)
    }
}

/// The log modes (`log_field` 1, `log_brdf` 2; 0 otherwise) need an environment set (its
/// height-field visibility joins the sum): vectors per receiver beyond `V_s`.
fn log_mode(scene: &Scene) -> u32 {
    if !crate::rules::lighting::has_environment(scene) {
        return 0;
    }
    match scene.gi.blocker_shading {
        BlockerShading::LogField => 1,
        BlockerShading::LogBrdf => 2,
        _ => 0,
    }
}

/// Vectors per receiver in [`OUTPUT_BUFFER`]: `V_s`; with `log_field` the environment's
/// `exp*(f_hf + Σ f_i)`; with `log_brdf` also its diffuse and glossy transfers.
fn vectors(scene: &Scene) -> usize {
    match log_mode(scene) {
        0 => 1,
        1 => 2,
        _ => 4,
    }
}

/// `√(4π/(2l+1))` times the log-SH Phong lobe of exponent `s` ([`shexp::log_phong_zh`], `ε_ρ`),
/// for [`BlockerPush::log_phong`].
fn log_phong(n: usize, s: f64) -> [f32; 8] {
    let mut out = [0f32; 8];
    for (l, z) in shexp::log_phong_zh(n, s, LOG_BRDF_EPSILON).into_iter().enumerate() {
        out[l] = ((4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * z) as f32;
    }
    out
}

/// The [`SPHERES_BUFFER`] data: per sphere the centre as a high and a low f32 and the radius
/// (radius 0: an empty slot, skipped).
pub(crate) fn sphere_data(spheres: &[SphereBlocker]) -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity(spheres.len().max(1) * 2);
    for b in spheres {
        let c = b.center.to_array();
        let hi = c.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (c[i] - f64::from(hi[i])) as f32);
        out.push([hi[0], hi[1], hi[2], b.radius as f32]);
        out.push([lo[0], lo[1], lo[2], 0.0]);
    }
    if out.is_empty() {
        out.resize(2, [0.0; 4]);
    }
    out
}

/// The [`QUAD_BUFFER`] data: per node of [`SphereQuadrature::pipeline`] its weight, then
/// the `n²` basis values.
fn quad_data(q: &SphereQuadrature) -> Vec<f32> {
    let mut out = Vec::with_capacity(q.len() * (q.order() * q.order() + 1));
    for (i, w) in q.weights().iter().enumerate() {
        out.push(*w as f32);
        out.extend(q.basis(i).iter().map(|v| *v as f32));
    }
    out
}

/// The [`CONSTS_BUFFER`] data: `K_l^m` (as `glsl/inc/hfgi_sh.glsl` reads it), the OL
/// method's `a` and `b` tables of order `n`, then `√(4π/(2l+1))` times the log-SH diffuse
/// BRDF's ZH (`log_brdf`; [`crate::math::shexp::log_diffuse_zh`]), then with the matched
/// log-ZH its table as `√(4π/(2l+1))·z_l/u` ([`crate::math::logcap::MatchedCaps`]).
fn consts_data(n: usize, matched: bool) -> Vec<f32> {
    let mut out: Vec<f32> = super::shade::klm_table(n).to_vec();
    let (a, b) = if n >= 2 { (shexp::OL_A[n - 2], shexp::OL_B[n - 2]) } else { ([1.0; 49], [1.0; 49]) };
    out.extend(a.iter().map(|v| *v as f32));
    out.extend(b.iter().map(|v| *v as f32));
    let mut brdf = [0f32; crate::constants::MAX_SH_ORDER as usize];
    for (l, z) in shexp::log_diffuse_zh(n, LOG_BRDF_EPSILON).into_iter().enumerate() {
        brdf[l] = ((4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * z) as f32;
    }
    out.extend(brdf);
    if matched {
        let t = crate::math::logcap::MatchedCaps::get(n).table();
        out.extend(t.iter().enumerate().map(|(i, z)| {
            let l = i % n;
            ((4.0 * std::f64::consts::PI / (2 * l + 1) as f64).sqrt() * z) as f32
        }));
    }
    out
}

/// Key lights are shadowed by the exact cap overlap (`gi.blocker_key_lights = "overlap"`, with
/// spheres), not by the product with `V_s`.
pub(crate) fn key_overlap(scene: &Scene) -> bool {
    !scene.spheres.is_empty() && scene.gi.blocker_key_lights == BlockerKeyLights::Overlap
}

/// The log modes use the matched log-ZH (not with `primal`, which has no logs).
fn matched(scene: &Scene) -> bool {
    scene.gi.blocker_log_cap == BlockerLogCap::Matched && scene.gi.blocker_shading != BlockerShading::Primal
}

/// The [`TRIPLE_BUFFER`] data: every ordered `(i, j, k)` of the order-n triple product as
/// `(i | j << 8 | k << 16, γ bits)` (as `hfgi.shade.triple`).
fn triple_data(n: usize) -> Vec<[u32; 2]> {
    crate::math::triple::triple(n)
        .entries
        .iter()
        .map(|&(i, j, k, g)| [i as u32 | (j as u32) << 8 | (k as u32) << 16, (g as f32).to_bits()])
        .collect()
}

/// The buffers `(name, bytes)` the pass creates, in creation order (also for
/// [`crate::frame::memory`]); none without spheres.
pub(crate) fn buffer_sizes(scene: &Scene) -> Vec<(&'static str, u64)> {
    if scene.spheres.is_empty() {
        return Vec::new();
    }
    let n = scene.gi.sh_order;
    let (ww, wh) = scene.gi.working_size(scene.field.width(), scene.field.height());
    let q = SphereQuadrature::pipeline_len(n);
    let vectors = vectors(scene);
    vec![
        (SPHERES_BUFFER, (scene.spheres.len() * 32) as u64),
        (QUAD_BUFFER, (q * (n * n + 1) * 4) as u64),
        (CONSTS_BUFFER, (consts_data(n, matched(scene)).len() * 4) as u64),
        (TRIPLE_BUFFER, (triple_data(n).len() * 8) as u64),
        (OUTPUT_BUFFER, (ww * wh * n * n * vectors * 4) as u64),
    ]
}

/// The sphere blockers' visibility pass (created only for scenes with spheres).
pub struct BlockerPass {
    pipeline: ComputePipeline,
    descriptors: vk::DescriptorSet,
    buffers: Vec<Buffer>, // spheres, quad, consts, triple
    output: Buffer,
    push: BlockerPush,
    order: usize,
    view_dependent: bool,
}

impl BlockerPass {
    pub fn new(ctx: &Context, pyramid: &HeightPyramid, vis: &VisibilityPass, scene: &Scene) -> Result<Self> {
        let n = scene.gi.sh_order;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let sizes = buffer_sizes(scene);
        let q = SphereQuadrature::pipeline(n);
        let triples = triple_data(n);
        let datas: [Vec<u8>; 4] = [
            bytemuck::cast_slice(&sphere_data(&scene.spheres)).to_vec(),
            bytemuck::cast_slice(&quad_data(&q)).to_vec(),
            bytemuck::cast_slice(&consts_data(n, matched(scene))).to_vec(),
            bytemuck::cast_slice(&triples).to_vec(),
        ];
        let mut bufs: Vec<Buffer> = Vec::new();
        let mut pipeline = None;
        let made = (|| -> Result<vk::DescriptorSet> {
            for (i, (name, size)) in sizes.into_iter().enumerate() {
                let b = Buffer::new(ctx, name, size, usage, MemoryLocation::GpuOnly)?;
                if let Some(bytes) = datas.get(i) {
                    debug_assert_eq!(size, bytes.len() as u64, "{name}");
                    memory::upload(ctx, &b, 0, bytes)?;
                }
                bufs.push(b);
            }
            let p = pipeline.insert(Self::create_pipeline(ctx, scene)?);
            p.allocate_set(
                ctx,
                &[
                    Bind::Buffer(pyramid.levels_buffer()),
                    Bind::Buffer(&bufs[0]),
                    Bind::Buffer(&bufs[1]),
                    Bind::Buffer(&bufs[2]),
                    Bind::Buffer(vis.buffer()),
                    Bind::Buffer(&bufs[4]),
                    Bind::Buffer(&bufs[3]),
                ],
            )
        })();
        let descriptors = match made {
            Ok(d) => d,
            Err(e) => {
                bufs.into_iter().for_each(|b| b.destroy(ctx));
                if let Some(mut p) = pipeline {
                    p.destroy(ctx);
                }
                return Err(e);
            }
        };
        let output = bufs.pop().expect("output");
        // bufs: spheres, quad, consts, triple
        debug_assert!(log_mode(scene) == 0 || vis.set_kinds().first() == Some(&SetKind::Environment));
        let push = Self::push_constants(scene, pyramid.work(), q.len(), triples.len());
        let mut pass = Self {
            pipeline: pipeline.expect("pipeline"),
            descriptors,
            buffers: bufs,
            output,
            push,
            order: n,
            view_dependent: log_mode(scene) == 2,
        };
        pass.set_view(scene.camera.position, f64::from(scene.material.exponent));
        Ok(pass)
    }

    /// The pass's pipeline, specialised for `scene`'s order and blocker settings.
    fn create_pipeline(ctx: &Context, scene: &Scene) -> Result<ComputePipeline> {
        let n = scene.gi.sh_order;
        let exp = (scene.gi.blocker_exp == BlockerExp::Linear) as u32;
        let primal = scene.gi.blocker_shading == BlockerShading::Primal;
        ComputePipeline::new(
            ctx,
            &shaders::VISIBILITY_BLOCKERS_COMP,
            &[DescriptorKind::StorageBuffer; 7],
            std::mem::size_of::<BlockerPush>() as u32,
            &[
                (0, n as u32),
                (1, exp),
                (2, log_mode(scene)),
                (3, primal as u32),
                (4, matched(scene) as u32),
                (5, scene.gi.storage.spec()),
            ],
            1,
        )
    }

    /// The push constants on the working grid `(ww, wh)`, with `quad_count` quadrature nodes
    /// and `triple_count` triple-product entries (the view's part from [`Self::set_view`]).
    fn push_constants(scene: &Scene, (ww, wh): (u32, u32), quad_count: usize, triple_count: usize) -> BlockerPush {
        BlockerPush {
            width: scene.field.width() as u32,
            height: scene.field.height() as u32,
            work_width: ww,
            work_height: wh,
            sphere_count: scene.spheres.len() as u32,
            quad_count: quad_count as u32,
            texel_size: scene.texel_size as f32,
            log_eps: scene.gi.blocker_epsilon.ln() as f32,
            ratio: scene.gi.blocker_ratio as u32,
            env_offset: 0, // the environment set is the first set (rules::lighting::light_sets)
            ol_step: shexp::OL_STEP as f32,
            triple_count: triple_count as u32,
            ..Default::default()
        }
    }

    /// `log_brdf`: the camera and the Phong exponent of the glossy transfer (push constants;
    /// [`crate::frame::Renderer::set_camera`] and `set_material` call it).
    pub(crate) fn set_view(&mut self, camera: glam::DVec3, exponent: f64) {
        let cam = camera.to_array();
        let hi = cam.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (cam[i] - f64::from(hi[i])) as f32);
        self.push.camera = [hi[0], hi[1], hi[2], 0.0];
        self.push.camera_lo = [lo[0], lo[1], lo[2], 0.0];
        self.push.log_phong = log_phong(self.order, exponent);
    }

    /// Whether the pass computes the glossy transfer (`log_brdf`), which depends on the view:
    /// a camera or Phong-exponent change then re-runs the stage.
    pub(crate) fn view_dependent(&self) -> bool {
        self.view_dependent
    }

    pub fn record(&self, rec: &mut Recorder) {
        rec.scope(STAGE_BLOCKERS, |ctx, cmd| {
            let g = [
                groups(self.push.work_width, crate::constants::WORKGROUP),
                groups(self.push.work_height, crate::constants::WORKGROUP),
                1,
            ];
            self.pipeline.dispatch(ctx, cmd, self.descriptors, bytemuck::bytes_of(&self.push), g);
            barrier::compute_to_compute(ctx, cmd);
        });
    }

    /// The sphere slots (binding 10 of the shading shader: the key lights' shadows).
    pub fn spheres(&self) -> &Buffer {
        &self.buffers[0]
    }

    /// The visibility vectors (binding 9 of the shading shader).
    pub fn output(&self) -> &Buffer {
        &self.output
    }

    /// Reads the blockers' visibility back: receivers × `n²` floats (twice in log mode; waits).
    pub fn read(&self, ctx: &Context) -> Result<Vec<f32>> {
        memory::download_f32(ctx, &self.output, 0, self.output.size / 4)
    }

    /// The sphere buffer's new contents for `spheres` (as many as the slots), for the live
    /// inputs' `inputs.update`.
    pub(crate) fn sphere_update(&self, spheres: &[SphereBlocker]) -> (vk::Buffer, u64, Vec<u8>) {
        (self.buffers[0].raw, 0, bytemuck::cast_slice(&sphere_data(spheres)).to_vec())
    }

    pub fn memory_bytes(&self) -> u64 {
        self.buffers.iter().map(|b| b.size).sum::<u64>() + self.output.size
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.buffers.drain(..).for_each(|b| b.destroy(ctx));
        self.output.destroy(ctx);
    }
}
