//! Stage `shade.direct` (NS09 §7; docs/direct.md §5–6): direct diffuse and Phong shading at
//! full resolution from the light sets' SH visibility.
//!
//! Output: [`ShadePass::output`], one RGB texel per field texel in the [`ShadingFormat`] of
//! `gi.shading_storage` (an `f32` triple, or one shared-exponent word), [`planes`] planes of
//! `W × H`: [`LAYER_TOTAL`], [`LAYER_DIRECT`], [`LAYER_INDIRECT`] and, for a glossy surface
//! only (`material.specular` set at creation), [`LAYER_GLOSSY`] and the internal
//! [`PLANE_GLOSSY_DIRECT`], [`PLANE_GLOSSY_INDIRECT`] (zero until an indirect bounce writes them).
//! Each shading dispatch recomposes total and glossy, so direct and indirect may be updated on
//! different frames (docs/indirect.md §5). After `record`, a compute→compute barrier has been
//! recorded; for vertex/fragment or transfer reads add the matching barrier.

use std::f64::consts::PI;

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::shared::ShadePush;
use super::visibility::VisibilityPass;
use crate::constants;
use crate::error::Result;
use crate::math::azimuth::AzimuthSet;
use crate::math::{sh, triple};
pub use crate::rules::lighting::{cap_solid_angle, set_lighting, window_solid_angle};
use crate::rules::lighting::{light_sets, SetKind};
use crate::scene::model::{Albedo, DiffuseLobe, Scene};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

mod format;
pub use format::ShadingFormat;

pub const STAGE_DIRECT: &str = super::stages::stage_name("shade.direct");

// The planes come from src/constants.rs, which the shaders see as HFGI_PLANE_*.
pub const LAYER_TOTAL: usize = constants::PLANE_TOTAL as usize;
pub const LAYER_DIRECT: usize = constants::PLANE_DIRECT as usize;
pub const LAYER_INDIRECT: usize = constants::PLANE_INDIRECT as usize;
pub const LAYER_GLOSSY: usize = constants::PLANE_GLOSSY as usize;
/// Internal planes: glossy exit radiance of the direct light and of the indirect bounces
/// (their sum is [`LAYER_GLOSSY`]).
pub const PLANE_GLOSSY_DIRECT: usize = constants::PLANE_GLOSSY_DIRECT as usize;
pub const PLANE_GLOSSY_INDIRECT: usize = constants::PLANE_GLOSSY_INDIRECT as usize;
/// Planes in the shading buffer of a glossy surface ([`planes`]).
pub const PLANES: usize = constants::PLANES as usize;

/// Whether the shading buffer has the glossy planes: the surface has a specular colour at
/// creation (`Renderer::set_material` cannot add one later; docs/integration.md §1).
pub fn glossy_planes(scene: &Scene) -> bool {
    scene.material.specular.is_some()
}

/// Planes in `scene`'s shading buffer: [`PLANES`] for a glossy surface, the three exported
/// diffuse layers (total, direct, indirect) otherwise.
pub fn planes(scene: &Scene) -> usize {
    if glossy_planes(scene) {
        PLANES
    } else {
        constants::PLANES_DIFFUSE as usize
    }
}
/// Layer names as exported (CONVENTIONS.md): the total is the default layer.
pub const LAYER_NAMES: [&str; 4] = ["", "direct", "indirect", "glossy"];

/// `K_l^|m|` (times √2 for m ≠ 0) at index `l(l+1)+m`, as `glsl/inc/hfgi_sh.glsl` reads it.
pub(crate) fn klm_table(n: usize) -> [f32; (constants::MAX_SH_ORDER * constants::MAX_SH_ORDER) as usize] {
    const N: usize = constants::MAX_SH_ORDER as usize;
    let mut klm = [0f32; N * N];
    for l in 0..n {
        for m in 0..=l {
            let k = sh::k_lm(l, m) * if m > 0 { std::f64::consts::SQRT_2 } else { 1.0 };
            klm[l * (l + 1) + m] = k as f32;
        }
    }
    klm
}

/// The constants block of the shader: K_l^m table, rotated-ZH band factors (the diffuse lobe of
/// `gi.diffuse_lobe`, the Phong lobe), triple count.
pub(crate) fn constants(n: usize, lobe: DiffuseLobe, exponent: f64, triple_count: u32) -> Vec<u32> {
    const N: usize = constants::MAX_SH_ORDER as usize;
    let klm = klm_table(n);
    let cc = crate::rules::scene::diffuse_lobe(n, lobe);
    let mut diffuse = [0f32; N];
    let mut glossy = [0f32; N];
    for l in 0..n {
        let band = (4.0 * PI / (2 * l + 1) as f64).sqrt();
        diffuse[l] = (band * cc[l]) as f32;
        // Normalised Phong lobe: z_l = √((2l+1)/4π)·e^(−l²/2S), so band·z_l = e^(−l²/2S).
        glossy[l] = (-((l * l) as f64) / (2.0 * exponent)).exp() as f32;
    }
    let mut out: Vec<u32> = Vec::with_capacity(84);
    out.extend(klm.iter().map(|v| v.to_bits()));
    out.extend(diffuse.iter().map(|v| v.to_bits()));
    out.extend(glossy.iter().map(|v| v.to_bits()));
    out.push(triple_count);
    out
}

/// What the pass uploads (light, triple, albedo, constants), computed from the scene (one
/// source for the pass and [`crate::frame::memory`]).
pub(crate) struct ShadeData {
    light: Vec<[f32; 4]>,
    entries: Vec<[u32; 2]>,
    albedo: Vec<[f32; 4]>,
    consts: Vec<u32>,
}

/// The `hfgi.shade.light` data of `sets` (in buffer order): each set's `n²` RGB lighting
/// ([`set_lighting`]) as `vec4`s, then per set its cap — a key light's unit direction and
/// angular radius (`w > 0`), zeros for the environment — for the spheres' key-light shadows
/// (`gi.blocker_key_lights = "overlap"`), then per set its product matrix
/// ([`product_matrix`], `n⁴` `vec4`s).
pub(crate) fn light_data(scene: &Scene, sets: &[(SetKind, AzimuthSet)]) -> Vec<[f32; 4]> {
    let lighting: Vec<Vec<[f64; 3]>> = sets.iter().map(|(k, set)| set_lighting(scene, *k, set)).collect();
    let rgba = |c: &[f64; 3]| [c[0] as f32, c[1] as f32, c[2] as f32, 0.0];
    let mut out: Vec<[f32; 4]> = lighting.iter().flatten().map(rgba).collect();
    out.extend(sets.iter().map(|(k, _)| match k {
        SetKind::KeyLight(i) => {
            let l = &scene.key_lights[*i];
            let d = l.direction.normalize();
            [d.x as f32, d.y as f32, d.z as f32, l.angular_radius as f32]
        }
        SetKind::Environment => [0.0; 4],
    }));
    let t = triple::triple(scene.gi.sh_order);
    out.extend(lighting.iter().flat_map(|l| product_matrix(t, l)).map(|c| rgba(&c)));
    out
}

/// The SH product with lighting `l` as a matrix (docs/direct.md §6): `M[j][k] = Σ_i Γ_ijk l_i`
/// (RGB, row-major, `n² × n²`, f64), so that the incident radiance of visibility `V` is
/// `T_k = Σ_j V_j M[j][k]`: one matrix–vector product per texel and set (docs/performance.md §19).
pub(crate) fn product_matrix(t: &triple::Triple, l: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n2 = t.n * t.n;
    let mut m = vec![[0.0; 3]; n2 * n2];
    for &(i, j, k, g) in &t.entries {
        let (i, j, k) = (i as usize, j as usize, k as usize);
        for c in 0..3 {
            m[j * n2 + k][c] += g * l[i][c];
        }
    }
    m
}

impl ShadePush {
    /// The shading camera (glossy view vector), as a high and a low f32 (docs/hard-cases.md):
    /// the shader forms (camera − P) + camera_lo, exact to f32 of the result even for heights
    /// near 1e7.
    pub(crate) fn set_camera(&mut self, position: glam::DVec3) {
        let cam = position.to_array();
        let hi = cam.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (cam[i] - hi[i] as f64) as f32);
        self.camera = [hi[0], hi[1], hi[2], 0.0];
        self.camera_lo = [lo[0], lo[1], lo[2], 0.0];
    }

    /// The material's push fields: constant albedo (or the map flag), specular and its switch.
    pub(crate) fn set_material(&mut self, m: &crate::scene::model::Material) {
        let (albedo_map, albedo) = match &m.albedo {
            Albedo::Map(_) => (1, [0.0; 4]),
            Albedo::Constant(a) => (0, [a[0], a[1], a[2], 0.0]),
        };
        let spec = m.specular.unwrap_or([0.0; 3]);
        self.albedo_map = albedo_map;
        self.albedo = albedo;
        self.glossy = m.specular.is_some() as u32;
        self.specular = [spec[0], spec[1], spec[2], 0.0];
    }
}

impl ShadeData {
    pub(crate) fn new(scene: &Scene) -> Self {
        let n = scene.gi.sh_order;
        let light = light_data(scene, &light_sets(scene));
        let t = triple::triple(n);
        let entries: Vec<[u32; 2]> = t
            .entries
            .iter()
            .map(|&(i, j, k, g)| [i as u32 | (j as u32) << 8 | (k as u32) << 16, (g as f32).to_bits()])
            .collect();
        let albedo: Vec<[f32; 4]> = match &scene.material.albedo {
            Albedo::Map(m) => m.iter().map(|a| [a[0], a[1], a[2], 0.0]).collect(),
            Albedo::Constant(_) => vec![[0.0; 4]],
        };
        let consts = constants(n, scene.gi.diffuse_lobe, scene.material.exponent as f64, entries.len() as u32);
        Self { light, entries, albedo, consts }
    }

    /// The bytes of the uploaded buffers, in the order of [`upload_sizes`].
    pub(crate) fn uploads(&self) -> [&[u8]; 4] {
        [
            bytemuck::cast_slice::<_, u8>(&self.light),
            bytemuck::cast_slice(&self.entries),
            bytemuck::cast_slice(&self.albedo),
            bytemuck::cast_slice(&self.consts),
        ]
    }
}

/// The uploaded buffers `(name, bytes)` in creation order, sized without building the data
/// (an albedo map would be a full-resolution copy): [`upload_bytes`] of the lengths
/// [`ShadeData::new`] produces (the pass checks they agree in debug builds).
pub(crate) fn upload_sizes(scene: &Scene) -> [(&'static str, u64); 4] {
    let n = scene.gi.sh_order;
    let albedo = match &scene.material.albedo {
        Albedo::Map(m) => m.len(),
        Albedo::Constant(_) => 1,
    };
    let triples = triple::triple(n).entries.len();
    [
        ("hfgi.shade.light", upload_bytes(light_sets(scene).len() * (n * n + 1 + n * n * n * n) * 16)),
        ("hfgi.shade.triple", upload_bytes(triples * 8)),
        ("hfgi.shade.albedo", upload_bytes(albedo * 16)),
        (
            "hfgi.shade.consts",
            upload_bytes(constants(n, scene.gi.diffuse_lobe, scene.material.exponent as f64, triples as u32).len() * 4),
        ),
    ]
}

/// Specialization constants of `glsl/shade/direct.comp.glsl`, in its direct mode
/// (`shade.direct`, `next_stride = None`) or its indirect mode (`indirect.shade`:
/// `Some(floats per channel of the radiance levels buffer)`, where it writes the next bounce's
/// input).
/// The indirect mode reads `U`'s [`u_coefficients`](crate::rules::scene::u_coefficients).
pub(crate) fn spec(scene: &Scene, next_stride: Option<u32>) -> [(u32, u32); 10] {
    let (w, h) = (scene.field.width(), scene.field.height());
    [
        (0, scene.gi.sh_order as u32),
        (1, next_stride.is_some() as u32),
        (2, super::renderer::vector_pyramid(scene) as u32),
        (3, super::blockers::shading_mode(scene)),
        (4, scene.gi.storage.spec()),
        (5, glossy_planes(scene) as u32),
        (6, next_stride.unwrap_or(0)),
        (7, crate::rules::scene::u_coefficients(scene) as u32),
        (8, (scene.gi.working_size(w, h) == (w, h)) as u32),
        (9, ShadingFormat::of(scene).packed_flag()),
    ]
}

/// Names of the shading buffer and of the incident-radiance buffer.
pub(crate) const OUTPUT_BUFFER: &str = "hfgi.shade.output";
pub(crate) const INCIDENT_BUFFER: &str = "hfgi.shade.incident";

/// Bytes requested for an uploaded buffer of `len` bytes (at least 16).
pub(crate) fn upload_bytes(len: usize) -> u64 {
    len.max(16) as u64
}

/// Bytes of [`OUTPUT_BUFFER`]: [`planes`] planes of `W × H` texels of [`ShadingFormat::of`].
pub(crate) fn output_bytes(scene: &Scene) -> u64 {
    (planes(scene) * scene.field.width() * scene.field.height()) as u64 * ShadingFormat::of(scene).texel_bytes()
}

/// Bytes of [`INCIDENT_BUFFER`]: `T` per texel (`n²` `vec4`s) for the glossy vector pyramid
/// (docs/indirect.md §1); 16 bytes otherwise.
pub(crate) fn incident_bytes(scene: &Scene) -> u64 {
    let (w, h, n) = (scene.field.width(), scene.field.height(), scene.gi.sh_order);
    if super::renderer::vector_pyramid(scene) {
        (w * h * n * n * 16) as u64
    } else {
        16
    }
}

/// The direct shading pass.
pub struct ShadePass {
    pipeline: ComputePipeline,
    descriptors: vk::DescriptorSet,
    buffers: Vec<Buffer>, // light, triple, albedo, consts
    output: Buffer,
    incident: Buffer,
    push: ShadePush,
    /// [`planes`] of the scene at creation.
    planes: usize,
    /// The planes' texel format ([`ShadingFormat::of`] the scene at creation).
    format: ShadingFormat,
}

/// The shading shader's bindings (glsl/shade/direct.comp.glsl, both modes): texel views of
/// the heights, `V` or `U`, the light and the triple table, which it reads per texel or per
/// triple (docs/performance.md §17); storage buffers for the rest.
pub(crate) const BINDINGS: [DescriptorKind; 11] = {
    let mut k = [DescriptorKind::StorageBuffer; 11];
    k[0] = DescriptorKind::TexelBuffer;
    k[1] = DescriptorKind::TexelBuffer;
    k[2] = DescriptorKind::TexelBuffer;
    k[3] = DescriptorKind::TexelBuffer;
    k
};

impl ShadePass {
    /// `blockers`: the sphere blockers' pass (its visibility buffer and its spheres, for the
    /// key lights' shadows), when the scene has spheres.
    pub fn new(
        ctx: &Context,
        pyramid: &HeightPyramid,
        vis: &VisibilityPass,
        blockers: Option<&super::blockers::BlockerPass>,
        scene: &Scene,
    ) -> Result<Self> {
        let data = ShadeData::new(scene);
        let mut bufs: Vec<Buffer> = Vec::new();
        let mut pipeline = None;
        let made = (|| -> Result<vk::DescriptorSet> {
            Self::create_buffers(ctx, &mut bufs, scene, &data)?;
            let p = pipeline.insert(ComputePipeline::new(
                ctx,
                &shaders::SHADE_DIRECT_COMP,
                &BINDINGS,
                std::mem::size_of::<ShadePush>() as u32,
                &spec(scene, None),
                1,
            )?);
            p.allocate_set(
                ctx,
                &[
                    Bind::Texel(pyramid.levels_buffer()),
                    Bind::Texel(vis.buffer()),
                    Bind::Texel(&bufs[0]),
                    Bind::Texel(&bufs[1]),
                    Bind::Buffer(&bufs[2]),
                    Bind::Buffer(&bufs[3]),
                    Bind::Buffer(&bufs[4]),
                    Bind::Buffer(&bufs[4]), // the next bounce's level 0: unused by the direct mode
                    Bind::Buffer(&bufs[5]),
                    Bind::Buffer(blockers.map_or(&bufs[4], |b| b.output())), // unread without spheres
                    Bind::Buffer(blockers.map_or(&bufs[4], |b| b.spheres())),
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
        let incident = bufs.pop().expect("incident");
        let output = bufs.pop().expect("output");
        let push = Self::push_constants(scene, pyramid.work(), vis.set_count());
        let (planes, format) = (planes(scene), ShadingFormat::of(scene));
        let pipeline = pipeline.expect("pipeline");
        Ok(Self { pipeline, descriptors, buffers: bufs, output, incident, push, planes, format })
    }

    /// Creates into `bufs` (which the caller destroys on an error) the uploaded buffers of
    /// `data` ([`upload_sizes`] order), then the output buffer (cleared) and the incident buffer.
    fn create_buffers(ctx: &Context, bufs: &mut Vec<Buffer>, scene: &Scene, data: &ShadeData) -> Result<()> {
        let usage = crate::vk::memory::PASS_BUFFER_USAGE;
        // Texel views of the light (vec4s) and the triple table (uvec2s), docs/performance.md §17.
        let views = [Some(vk::Format::R32G32B32A32_UINT), Some(vk::Format::R32G32_UINT), None, None];
        for (((name, size), bytes), view) in upload_sizes(scene).into_iter().zip(data.uploads()).zip(views) {
            debug_assert_eq!(size, upload_bytes(bytes.len()), "{name}");
            let b = Buffer::new(ctx, name, size, usage, MemoryLocation::GpuOnly)?;
            let b = match view {
                Some(format) => b.with_texel_view(ctx, format)?,
                None => b,
            };
            if !bytes.is_empty() {
                memory::upload(ctx, &b, 0, bytes)?;
            }
            bufs.push(b);
        }
        let out = Buffer::new(ctx, OUTPUT_BUFFER, output_bytes(scene), usage, MemoryLocation::GpuOnly)?;
        // Planes not written by a frame (indirect with bounces = 0) must read as zero.
        let cleared = memory::zero(ctx, &out);
        bufs.push(out);
        cleared?;
        let inc_bytes = incident_bytes(scene);
        bufs.push(Buffer::new(ctx, INCIDENT_BUFFER, inc_bytes, usage, MemoryLocation::GpuOnly)?);
        Ok(())
    }

    /// The push constants on the working grid `(ww, wh)` with `set_count` light sets, the
    /// scene's camera and material set.
    fn push_constants(scene: &Scene, (ww, wh): (u32, u32), set_count: usize) -> ShadePush {
        let (w, h) = (scene.field.width(), scene.field.height());
        let mut push = ShadePush {
            width: w as u32,
            height: h as u32,
            work_width: ww,
            work_height: wh,
            set_count: set_count as u32,
            wrap: scene.wrap as u32,
            texel_size: scene.texel_size as f32,
            sphere_count: scene.spheres.len() as u32,
            key_overlap: super::blockers::key_overlap(scene) as u32,
            u_scale: 1.0,
            ..Default::default()
        };
        push.set_camera(scene.camera.position);
        push.set_material(&scene.material);
        push
    }

    pub fn record(&self, rec: &mut Recorder) {
        rec.scope(STAGE_DIRECT, |ctx, cmd| {
            let g = [
                groups(self.push.width, crate::constants::WORKGROUP),
                groups(self.push.height, crate::constants::WORKGROUP),
                1,
            ];
            self.pipeline.dispatch(ctx, cmd, self.descriptors, bytemuck::bytes_of(&self.push), g);
            barrier::compute_to_compute(ctx, cmd);
        });
    }

    /// The shading buffer: [`ShadePass::planes`] planes × W×H texels of
    /// [`ShadePass::format`] (the module docs list them).
    pub fn output(&self) -> &Buffer {
        &self.output
    }

    /// The texel format of [`ShadePass::output`].
    pub fn format(&self) -> ShadingFormat {
        self.format
    }

    /// Planes in the shading buffer ([`planes`] of the scene at creation: 6, or 3 without the
    /// glossy ones).
    pub fn planes(&self) -> usize {
        self.planes
    }

    /// Light, triple, albedo, constants and output buffers, for the indirect mode of the
    /// shading shader (binding order of `glsl/shade/direct.comp.glsl`).
    pub fn bindings(&self) -> [&Buffer; 5] {
        [&self.buffers[0], &self.buffers[1], &self.buffers[2], &self.buffers[3], &self.output]
    }

    /// The incident SH radiance `T` of the direct light per texel (`n²` vec4), written only
    /// for the glossy vector pyramid.
    pub fn incident(&self) -> &Buffer {
        &self.incident
    }

    /// The push constants of the direct mode.
    pub fn push(&self) -> ShadePush {
        self.push
    }

    /// The push constants of the direct mode, for the live inputs (docs/integration.md §2).
    pub(crate) fn push_mut(&mut self) -> &mut ShadePush {
        &mut self.push
    }

    /// Reads layer `layer` back as RGB (waits); zeros for a glossy layer of a diffuse surface
    /// (it has no glossy planes).
    pub fn read_layer(&self, ctx: &Context, layer: usize) -> Result<Vec<[f32; 3]>> {
        let texels = (self.push.width * self.push.height) as usize;
        if layer >= self.planes && layer < PLANES {
            return Ok(vec![[0.0; 3]; texels]);
        }
        self.download_plane(ctx, layer)
    }

    /// Diagnostics: plane `plane` (< [`ShadePass::planes`]) of the shading buffer decoded to
    /// floats (RGB per texel), read back (waits).
    pub fn read_plane(&self, ctx: &Context, plane: usize) -> Result<Vec<f32>> {
        Ok(self.download_plane(ctx, plane)?.into_iter().flatten().collect())
    }

    /// Plane `plane` (< [`ShadePass::planes`]) read back and decoded (waits).
    fn download_plane(&self, ctx: &Context, plane: usize) -> Result<Vec<[f32; 3]>> {
        if plane >= self.planes {
            return Err(crate::error::Error::param("shading plane", plane, format!("< {}", self.planes)));
        }
        let bytes = (self.push.width * self.push.height) as u64 * self.format.texel_bytes();
        Ok(self.format.decode(&memory::download(ctx, &self.output, plane as u64 * bytes, bytes)?))
    }

    /// Diagnostics: the incident SH radiance `T` of the direct light (`W·H·n²` `vec4`s), read
    /// back (waits); `None` unless the glossy vector pyramid stores it.
    pub fn read_incident(&self, ctx: &Context) -> Result<Option<Vec<f32>>> {
        if self.incident.size <= 16 {
            return Ok(None);
        }
        memory::download_f32(ctx, &self.incident, 0, self.incident.size / 4).map(Some)
    }

    pub fn memory_bytes(&self) -> u64 {
        self.buffers.iter().map(|b| b.size).sum::<u64>() + self.output.size + self.incident.size
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.buffers.drain(..).for_each(|b| b.destroy(ctx));
        self.output.destroy(ctx);
        self.incident.destroy(ctx);
    }
}

#[cfg(test)]
mod tests;
