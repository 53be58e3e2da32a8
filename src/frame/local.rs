//! Stage `shade.local_lights` (docs/local-lights.md; SN08 thesis §4.3): the diffuse exit
//! radiance of the local spherical lights, added to the direct and total planes of
//! [`ShadePass::output`] right after `shade.direct` wrote them (the plan records both together,
//! so a frame never adds twice). f64 twin: [`crate::reference::local`].
//!
//! Buffers: `hfgi.local.lights` (3 `vec4` per slot: the centre's high f32 part and the radius,
//! the low part, the radiance; written at creation and by [`crate::frame::Renderer::set_local_lights`]
//! through `inputs.update`), `hfgi.local.nodes` (the `gi.local_light_azimuths` Gauss–Legendre
//! nodes and weights on `[−1, 1]`). Reads the heights (level 0 of the height pyramid's levels
//! buffer, absolute), the shading pass's albedo buffer; read-modify-writes its output. After
//! `record`, a compute→compute barrier has been recorded.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::pyramid::HeightPyramid;
use super::shade::ShadePass;
use super::shared::LocalPush;
use crate::error::Result;
use crate::math::quadrature::gauss_legendre;
use crate::scene::model::{Albedo, LocalLight, Material, Scene};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

pub const STAGE_LOCAL_LIGHTS: &str = super::stages::stage_name("shade.local_lights");

/// Debug names of the pass's buffers.
pub(crate) const LIGHTS_BUFFER: &str = "hfgi.local.lights";
pub(crate) const NODES_BUFFER: &str = "hfgi.local.nodes";

/// `vec4`s per light slot in [`LIGHTS_BUFFER`].
const VEC4S_PER_LIGHT: usize = 3;

/// The [`LIGHTS_BUFFER`] data of `lights`: per light the centre split into a high and a low
/// f32 (`hi + lo` = the f64 position; the shader forms `(hi − P) + lo`, exact near the
/// surface even for heights near 1e7), the radius, the radiance.
pub(crate) fn light_data(lights: &[LocalLight]) -> Vec<[f32; 4]> {
    let mut out = Vec::with_capacity(lights.len().max(1) * VEC4S_PER_LIGHT);
    for l in lights {
        let c = l.position.to_array();
        let hi = c.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (c[i] - f64::from(hi[i])) as f32);
        let r = l.radiance.map(|v| v as f32);
        out.push([hi[0], hi[1], hi[2], l.radius as f32]);
        out.push([lo[0], lo[1], lo[2], 0.0]);
        out.push([r[0], r[1], r[2], 0.0]);
    }
    if out.is_empty() {
        out.resize(VEC4S_PER_LIGHT, [0.0; 4]);
    }
    out
}

/// The [`NODES_BUFFER`] data: `k` Gauss–Legendre `(x, w)` pairs on `[−1, 1]` (the azimuths),
/// then the [`crate::constants::LOCAL_GLOSSY_NODES`] ones (the glossy lobe in elevation).
fn node_data(k: u32) -> Vec<[f32; 2]> {
    let (x, w) = gauss_legendre(k as usize);
    let (gx, gw) = gauss_legendre(crate::constants::LOCAL_GLOSSY_NODES as usize);
    x.iter().chain(&gx).zip(w.iter().chain(&gw)).map(|(x, w)| [*x as f32, *w as f32]).collect()
}

/// The buffers `(name, bytes)` the pass creates, in creation order (also for
/// [`crate::frame::memory`]); none without local lights.
pub(crate) fn buffer_sizes(scene: &Scene) -> Vec<(&'static str, u64)> {
    if scene.local_lights.is_empty() {
        return Vec::new();
    }
    let lights = (scene.local_lights.len() * VEC4S_PER_LIGHT * 16) as u64;
    let nodes = ((scene.gi.local_light_azimuths + crate::constants::LOCAL_GLOSSY_NODES) as usize * 8) as u64;
    vec![(LIGHTS_BUFFER, lights), (NODES_BUFFER, nodes)]
}

impl LocalPush {
    /// The material's push fields: constant albedo, or the map flag.
    pub(crate) fn set_material(&mut self, m: &Material) {
        match &m.albedo {
            Albedo::Map(_) => (self.albedo_map, self.albedo) = (1, [0.0; 4]),
            Albedo::Constant(a) => (self.albedo_map, self.albedo) = (0, [a[0], a[1], a[2], 0.0]),
        }
        let ks = m.specular.unwrap_or([0.0; 3]);
        self.glossy = m.specular.is_some() as u32;
        self.exponent = m.exponent;
        self.specular = [ks[0], ks[1], ks[2], 0.0];
    }

    /// The camera (the glossy view vector), as a high and a low f32 (as `ShadePush`).
    pub(crate) fn set_camera(&mut self, position: glam::DVec3) {
        let cam = position.to_array();
        let hi = cam.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (cam[i] - f64::from(hi[i])) as f32);
        self.camera = [hi[0], hi[1], hi[2], 0.0];
        self.camera_lo = [lo[0], lo[1], lo[2], 0.0];
    }
}

/// The local lights' shading pass (created only for scenes with local lights).
pub struct LocalLightPass {
    pipeline: ComputePipeline,
    descriptors: vk::DescriptorSet,
    lights: Buffer,
    nodes: Buffer,
    push: LocalPush,
}

impl LocalLightPass {
    pub fn new(ctx: &Context, pyramid: &HeightPyramid, shade: &ShadePass, scene: &Scene) -> Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST;
        let sizes = buffer_sizes(scene);
        let datas: [Vec<u8>; 2] = [
            bytemuck::cast_slice(&light_data(&scene.local_lights)).to_vec(),
            bytemuck::cast_slice(&node_data(scene.gi.local_light_azimuths)).to_vec(),
        ];
        let mut bufs: Vec<Buffer> = Vec::new();
        let mut pipeline = None;
        let made = (|| -> Result<vk::DescriptorSet> {
            for ((name, size), bytes) in sizes.into_iter().zip(&datas) {
                debug_assert_eq!(size, bytes.len() as u64, "{name}");
                let b = Buffer::new(ctx, name, size, usage, MemoryLocation::GpuOnly)?;
                memory::upload(ctx, &b, 0, bytes)?;
                bufs.push(b);
            }
            let p = pipeline.insert(ComputePipeline::new(
                ctx,
                &shaders::SHADE_LOCAL_COMP,
                &[DescriptorKind::StorageBuffer; 5],
                std::mem::size_of::<LocalPush>() as u32,
                &[
                    (0, super::shade::glossy_planes(scene) as u32),
                    (1, super::shade::ShadingFormat::of(scene).packed_flag()),
                ],
                1,
            )?);
            let [_, _, albedo, _, output] = shade.bindings();
            p.allocate_set(
                ctx,
                &[
                    Bind::Buffer(pyramid.levels_buffer()),
                    Bind::Buffer(&bufs[0]),
                    Bind::Buffer(&bufs[1]),
                    Bind::Buffer(albedo),
                    Bind::Buffer(output),
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
        let nodes = bufs.pop().expect("nodes");
        let lights = bufs.pop().expect("lights");
        let mut push = LocalPush {
            width: scene.field.width() as u32,
            height: scene.field.height() as u32,
            light_count: scene.local_lights.len() as u32,
            azimuths: scene.gi.local_light_azimuths,
            texel_size: scene.texel_size as f32,
            ..Default::default()
        };
        push.set_material(&scene.material);
        push.set_camera(scene.camera.position);
        Ok(Self { pipeline: pipeline.expect("pipeline"), descriptors, lights, nodes, push })
    }

    pub fn record(&self, rec: &mut Recorder) {
        rec.scope(STAGE_LOCAL_LIGHTS, |ctx, cmd| {
            let g = [
                groups(self.push.width, crate::constants::WORKGROUP),
                groups(self.push.height, crate::constants::WORKGROUP),
                1,
            ];
            self.pipeline.dispatch(ctx, cmd, self.descriptors, bytemuck::bytes_of(&self.push), g);
            barrier::compute_to_compute(ctx, cmd);
        });
    }

    /// The light buffer's new contents for `lights` (as many as the slots), for the live
    /// inputs' `inputs.update`.
    pub(crate) fn light_update(&self, lights: &[LocalLight]) -> (vk::Buffer, u64, Vec<u8>) {
        (self.lights.raw, 0, bytemuck::cast_slice(&light_data(lights)).to_vec())
    }

    /// The push constants, for the live inputs (material).
    pub(crate) fn push_mut(&mut self) -> &mut LocalPush {
        &mut self.push
    }

    pub fn memory_bytes(&self) -> u64 {
        self.lights.size + self.nodes.size
    }

    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.lights.destroy(ctx);
        self.nodes.destroy(ctx);
    }
}
