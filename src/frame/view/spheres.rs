//! The sphere blockers as the view draws them (docs/view.md §6): the UV sphere, the sphere
//! buffer's layout and the spheres' lighting.

use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::DVec3;

use crate::scene::model::{Environment, KeyLight, SphereBlocker};
use crate::vk::{Buffer, Context, GraphicsPipeline};

/// Stacks (latitude bands) of the UV sphere drawn per sphere blocker (docs/view.md §6).
pub const SPHERE_STACKS: u32 = 16;
/// Slices (longitude bands) of the UV sphere.
pub const SPHERE_SLICES: u32 = 32;
/// Vertices per sphere: two triangles per quad, no index buffer.
pub const SPHERE_VERTICES: u32 = 6 * SPHERE_STACKS * SPHERE_SLICES;

/// Name of the sphere buffer (host-visible, one [`GpuSphere`] per sphere slot).
pub(crate) const SPHERE_BUFFER: &str = "hfgi.view.spheres";
/// Name of the sphere lighting buffer (host-visible, [`SphereLighting::bytes`]).
pub(crate) const SPHERE_LIGHT_BUFFER: &str = "hfgi.view.sphere_light";

/// Whether a sphere blocker is drawn: a finite centre, a finite radius > 0 and a centre not
/// below `z = −1e9` (the renderer's unused slots hold a dark sphere at `z = −1e10`).
pub fn sphere_is_live(s: &SphereBlocker) -> bool {
    s.center.is_finite() && s.radius.is_finite() && s.radius > 0.0 && s.center.z >= -1e9
}

/// One sphere as the view shaders read it (std430, 48 bytes; `hfgi_ViewSphere` in
/// glsl/view/sphere.vert.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub(super) struct GpuSphere {
    /// Centre, high f32 part (xyz), radius (w).
    center_radius: [f32; 4],
    /// Centre, low part: `hi + lo` = the f64 centre.
    center_lo: [f32; 4],
    albedo: [f32; 4],
}

impl GpuSphere {
    pub(super) fn new(s: &SphereBlocker) -> Self {
        let c = s.center.to_array();
        let hi = c.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (c[i] - f64::from(hi[i])) as f32);
        let a = s.albedo.map(|v| v as f32);
        Self {
            center_radius: [hi[0], hi[1], hi[2], s.radius as f32],
            center_lo: [lo[0], lo[1], lo[2], 0.0],
            albedo: [a[0], a[1], a[2], 0.0],
        }
    }
}

/// The lighting of the view's spheres (docs/view.md §6): the environment's irradiance from its
/// first 9 SH coefficients and each key light as a distant cap. The fragment shader multiplies
/// them by the height field's cast shadow (an occlusion factor for the environment, a visible
/// fraction per key light), which this host copy does not model.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SphereLighting {
    /// Irradiance SH coefficients `Â_l · L_lm` (RGB), `k = l(l+1) + m < 9`, with `Â_0 = π`,
    /// `Â_1 = 2π/3`, `Â_2 = π/4` (missing coefficients are 0).
    pub env: [[f64; 3]; 9],
    /// Per key light: the unit direction `d`, `L · 2π(1 − cos α)`, the irradiance on a
    /// surface facing it (times `max(N·d, 0)` elsewhere), and the angular radius `α` (radians;
    /// the width of the field-shadow ramp, docs/view.md §6).
    pub key_lights: Vec<(DVec3, [f64; 3], f64)>,
}

impl SphereLighting {
    /// The lighting of `environment` (n² RGB SH coefficients, CONVENTIONS.md) and `key_lights`.
    pub fn new(environment: &Environment, key_lights: &[KeyLight]) -> Self {
        use std::f64::consts::PI;
        let mut env = [[0.0; 3]; 9];
        for (k, c) in environment.sh.iter().take(9).enumerate() {
            let a = match k {
                0 => PI,
                1..=3 => 2.0 * PI / 3.0,
                _ => PI / 4.0,
            };
            env[k] = c.map(|v| a * v);
        }
        let key_lights = key_lights
            .iter()
            .map(|l| {
                let solid = 2.0 * PI * (1.0 - l.angular_radius.cos());
                (l.direction.normalize_or_zero(), l.radiance.map(|v| v * solid), l.angular_radius)
            })
            .collect();
        Self { env, key_lights }
    }

    /// Irradiance `E(N)` at unit normal `n` without the height field's shadow (f64; what the
    /// fragment shader evaluates in f32 where the field blocks nothing: outside the field, or
    /// every horizon seen from the point below the lights' caps and below the horizontal).
    pub fn irradiance(&self, n: DVec3) -> [f64; 3] {
        let (x, y, z) = (n.x, n.y, n.z);
        let b = [
            0.282_094_791_773_878_1,
            0.488_602_511_902_919_9 * y,
            0.488_602_511_902_919_9 * z,
            0.488_602_511_902_919_9 * x,
            1.092_548_430_592_079_2 * x * y,
            1.092_548_430_592_079_2 * y * z,
            0.315_391_565_252_520_05 * (3.0 * z * z - 1.0),
            1.092_548_430_592_079_2 * x * z,
            0.546_274_215_296_039_6 * (x * x - y * y),
        ];
        let mut e = [0.0; 3];
        for (c, bk) in self.env.iter().zip(b) {
            (0..3).for_each(|i| e[i] += c[i] * bk);
        }
        for (d, l, _) in &self.key_lights {
            let cos = n.dot(*d).max(0.0);
            (0..3).for_each(|i| e[i] += l[i] * cos);
        }
        e
    }

    /// The buffer contents (std430, `Light` in glsl/view/sphere.frag.glsl): `uvec4` (x = key
    /// lights), 9 × `vec4` coefficients, then per key light `vec4` direction (xyz) and angular
    /// radius (w) and `vec4` irradiance.
    pub(super) fn bytes(&self) -> Vec<u8> {
        let mut v: Vec<[f32; 4]> = Vec::with_capacity(10 + 2 * self.key_lights.len());
        v.push(bytemuck::cast([self.key_lights.len() as u32, 0, 0, 0]));
        v.extend(self.env.iter().map(|c| [c[0] as f32, c[1] as f32, c[2] as f32, 0.0]));
        for (d, l, a) in &self.key_lights {
            v.push([d.x as f32, d.y as f32, d.z as f32, *a as f32]);
            v.push([l[0] as f32, l[1] as f32, l[2] as f32, 0.0]);
        }
        bytemuck::cast_slice(&v).to_vec()
    }
}

/// Bytes of [`SPHERE_BUFFER`] for `slots` spheres.
pub(crate) fn sphere_buffer_bytes(slots: usize) -> u64 {
    (slots.max(1) * std::mem::size_of::<GpuSphere>()) as u64
}

/// Bytes of [`SPHERE_LIGHT_BUFFER`] for `key_lights` key lights.
pub(crate) fn sphere_light_bytes(key_lights: usize) -> u64 {
    (16 * (10 + 2 * key_lights)) as u64
}

/// The sphere pipeline and its buffers (only while there are or were live spheres).
pub(super) struct SphereDraw {
    pub(super) pipeline: GraphicsPipeline,
    pub(super) set: vk::DescriptorSet,
    pub(super) spheres: Buffer,
    pub(super) light: Buffer,
    /// Spheres the buffer holds room for.
    pub(super) slots: usize,
    /// Key lights the lighting buffer holds room for.
    pub(super) key_slots: usize,
    /// Live spheres drawn (instances).
    pub(super) count: u32,
}

impl SphereDraw {
    pub(super) fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        self.spheres.destroy(ctx);
        self.light.destroy(ctx);
    }
}
