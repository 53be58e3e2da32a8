//! [`ViewPass`] between frames: the camera, the height range, the spheres and their lighting,
//! and the push constants they set.

use ash::vk;
use glam::DVec3;
use gpu_allocator::MemoryLocation;

use super::spheres::{GpuSphere, SphereDraw};
use super::{sphere_buffer_bytes, sphere_is_live, sphere_light_bytes, CameraModel, SphereLighting, ViewPass};
use super::{SPHERE_BUFFER, SPHERE_LIGHT_BUFFER};
use crate::error::{Error, Result};
use crate::frame::shared::ViewPush;
use crate::scene::model::{Camera, Environment, KeyLight, SphereBlocker};
use crate::shaders;
use crate::vk::graphics::GraphicsDesc;
use crate::vk::pipeline::Bind;
use crate::vk::{Buffer, Context, DescriptorKind, GraphicsPipeline};

impl ViewPass {
    /// The camera model for `camera` and `height_range`, its near/far planes fitted to the
    /// field's box and, with live spheres, their box too.
    fn fit_model(
        &self,
        camera: &Camera,
        height_range: (f32, f32),
        sphere_box: Option<(DVec3, DVec3)>,
    ) -> Result<CameraModel> {
        let (w, h, s) = (self.field.0, self.field.1, self.texel_size);
        let (lo, hi) = (f64::from(height_range.0), f64::from(height_range.1));
        let Some((smin, smax)) = sphere_box else {
            return CameraModel::new(camera, w, h, s, lo, hi);
        };
        let field = CameraModel::new(camera, w, h, s, lo, hi)?;
        let (x1, y1) = ((w.max(1) - 1) as f64 * s, (h.max(1) - 1) as f64 * s);
        let mut model =
            CameraModel::with_box(camera, DVec3::new(0.0, 0.0, lo).min(smin), DVec3::new(x1, y1, hi).max(smax), s)?;
        // A sphere far away pushes the far plane out and, through NEAR_RATIO, the near plane:
        // never past the field's own near plane, so that spheres cannot clip the field.
        model.near = model.near.min(field.near);
        Ok(model)
    }

    /// Sets the spheres drawn with the height field (docs/view.md §6): the live ones
    /// ([`sphere_is_live`]) of `spheres`, e.g. [`Renderer::live_scene`]`.spheres` after
    /// [`Renderer::set_spheres`]. Writes the host-visible sphere buffer now (no submit), so call
    /// it between frames: the GPU must not be executing a recorded frame of this pass (as after
    /// waiting for the frame's fence). The first live spheres create the sphere pipeline and its
    /// buffers, with room for `spheres.len()` spheres; more spheres later wait for the device to
    /// go idle and recreate them. Takes effect at the next [`ViewPass::record`]; the near/far
    /// planes are refitted to include the spheres.
    ///
    /// [`Renderer::live_scene`]: super::Renderer::live_scene
    /// [`Renderer::set_spheres`]: super::Renderer::set_spheres
    pub fn set_spheres(&mut self, ctx: &Context, spheres: &[SphereBlocker]) -> Result<()> {
        let live: Vec<&SphereBlocker> = spheres.iter().filter(|s| sphere_is_live(s)).collect();
        if let Some(k) = live.iter().position(|s| !s.albedo.iter().all(|a| a.is_finite())) {
            return Err(Error::param(format!("sphere {k} albedo"), format!("{:?}", live[k].albedo), "finite"));
        }
        let sphere_box = live.iter().fold(None, |acc: Option<(DVec3, DVec3)>, s| {
            let (a, b) = (s.center - DVec3::splat(s.radius), s.center + DVec3::splat(s.radius));
            Some(acc.map_or((a, b), |(lo, hi)| (lo.min(a), hi.max(b))))
        });
        let model = self.fit_model(&self.camera, self.height_range, sphere_box)?;
        if !live.is_empty() {
            self.ensure_spheres(ctx, spheres.len().max(live.len()), self.lighting.key_lights.len())?;
        }
        self.sphere_data = live.iter().map(|s| GpuSphere::new(s)).collect();
        self.write_buffers()?;
        self.sphere_box = sphere_box;
        self.model = model;
        self.update_push();
        Ok(())
    }

    /// Sets the lighting of the spheres (environment SH and key lights, docs/view.md §6;
    /// [`ViewPass::for_renderer`] takes the renderer's, [`ViewPass::new`] starts with none, i.e.
    /// black spheres). Writes the host-visible lighting buffer now if the sphere objects exist
    /// (the same rule as [`ViewPass::set_spheres`]: between frames).
    pub fn set_sphere_lighting(
        &mut self,
        ctx: &Context,
        environment: &Environment,
        key_lights: &[KeyLight],
    ) -> Result<()> {
        self.lighting = SphereLighting::new(environment, key_lights);
        if let Some(slots) = self.spheres.as_ref().map(|d| d.slots) {
            self.ensure_spheres(ctx, slots, self.lighting.key_lights.len())?;
        }
        self.write_buffers()
    }

    /// The lighting the spheres are drawn with.
    pub fn sphere_lighting(&self) -> &SphereLighting {
        &self.lighting
    }

    /// Live spheres the next frame draws (0 without sphere objects).
    pub fn sphere_count(&self) -> u32 {
        self.spheres.as_ref().map_or(0, |d| d.count)
    }

    /// Writes the host copies of the spheres and the lighting into the sphere objects (if any).
    fn write_buffers(&mut self) -> Result<()> {
        if let Some(d) = self.spheres.as_mut() {
            let bytes = self.lighting.bytes();
            d.light.mapped()?[..bytes.len()].copy_from_slice(&bytes);
            let bytes: &[u8] = bytemuck::cast_slice(&self.sphere_data);
            d.spheres.mapped()?[..bytes.len()].copy_from_slice(bytes);
            d.count = self.sphere_data.len() as u32;
        }
        Ok(())
    }

    /// Makes sure the sphere objects exist with room for `slots` spheres and `keys` key
    /// lights (recreating them after a device wait if they are smaller). New objects are
    /// written from the host copies ([`ViewPass::write_buffers`]).
    fn ensure_spheres(&mut self, ctx: &Context, slots: usize, keys: usize) -> Result<()> {
        if let Some(d) = &self.spheres {
            if d.slots >= slots && d.key_slots >= keys {
                return Ok(());
            }
        }
        let (slots, keys) = match &self.spheres {
            Some(d) => (slots.max(d.slots), keys.max(d.key_slots)),
            None => (slots, keys),
        };
        if let Some(old) = self.spheres.take() {
            // The old objects may still be read by a submitted frame.
            unsafe { ctx.device().device_wait_idle() }
                .map_err(|e| Error::Vulkan { call: "vkDeviceWaitIdle", result: e })?;
            old.destroy(ctx);
        }
        let extent = vk::Extent2D { width: self.camera.width, height: self.camera.height };
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let spheres = Buffer::new(ctx, SPHERE_BUFFER, sphere_buffer_bytes(slots), usage, MemoryLocation::CpuToGpu)?;
        let light =
            match Buffer::new(ctx, SPHERE_LIGHT_BUFFER, sphere_light_bytes(keys), usage, MemoryLocation::CpuToGpu) {
                Ok(b) => b,
                Err(e) => {
                    spheres.destroy(ctx);
                    return Err(e);
                }
            };
        let made = GraphicsPipeline::new(
            ctx,
            &GraphicsDesc {
                name: "view/spheres",
                vertex: &shaders::VIEW_SPHERE_VERT,
                fragment: &shaders::VIEW_SPHERE_FRAG,
                kinds: &[DescriptorKind::StorageBuffer; 3],
                push_size: std::mem::size_of::<ViewPush>() as u32,
                color_format: self.choice.color_format,
                depth_format: Some(self.choice.depth_format),
                depth_compare: vk::CompareOp::GREATER,
                samples: vk::SampleCountFlags::from_raw(self.choice.samples),
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                extent,
                max_sets: 1,
            },
        )
        .and_then(|mut p| {
            // Binding 2 is the heights buffer, which the pass knows by handle only: allocated
            // with a stand-in, then pointed at the heights.
            match p.allocate_set(ctx, &[Bind::Buffer(&spheres), Bind::Buffer(&light), Bind::Buffer(&spheres)]) {
                Ok(set) => {
                    let info = [self.heights];
                    let write = vk::WriteDescriptorSet::default()
                        .dst_set(set)
                        .dst_binding(2)
                        .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                        .buffer_info(&info);
                    unsafe { ctx.device().update_descriptor_sets(&[write], &[]) };
                    Ok((p, set))
                }
                Err(e) => {
                    p.destroy(ctx);
                    Err(e)
                }
            }
        });
        let (pipeline, set) = match made {
            Ok(v) => v,
            Err(e) => {
                spheres.destroy(ctx);
                light.destroy(ctx);
                return Err(e);
            }
        };
        self.spheres = Some(SphereDraw { pipeline, set, spheres, light, slots, key_slots: keys, count: 0 });
        self.write_buffers()
    }

    pub(super) fn update_push(&mut self) {
        let vp = self.model.eye_relative_view_projection().as_mat4();
        let eye = self.model.eye.to_array();
        let hi = eye.map(|v| v as f32);
        let lo = [0, 1, 2].map(|i| (eye[i] - hi[i] as f64) as f32);
        self.push = ViewPush {
            view_proj: vp.to_cols_array_2d(),
            width: self.field.0 as u32,
            height: self.field.1 as u32,
            texel_size: self.texel_size as f32,
            packed: self.shading_format.packed_flag(),
            eye: [hi[0], hi[1], hi[2], 0.0],
            eye_lo: [lo[0], lo[1], lo[2], 0.0],
        };
    }

    /// Moves the camera (position, target, fov; the image size must stay the same). Takes
    /// effect at the next [`ViewPass::record`].
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        if (camera.width, camera.height) != (self.camera.width, self.camera.height) {
            return Err(Error::param(
                "camera size",
                format!("{}×{}", camera.width, camera.height),
                format!(
                    "{}×{} (the pass's size; create a new ViewPass to resize)",
                    self.camera.width, self.camera.height
                ),
            ));
        }
        self.model = self.fit_model(camera, self.height_range, self.sphere_box)?;
        self.camera = camera.clone();
        self.update_push();
        Ok(())
    }

    /// Sets the height range that bounds the near/far planes (call when animated heights leave
    /// the range given at creation). Takes effect at the next [`ViewPass::record`].
    pub fn set_height_range(&mut self, lo: f32, hi: f32) -> Result<()> {
        self.model = self.fit_model(&self.camera, (lo, hi), self.sphere_box)?;
        self.height_range = (lo, hi);
        self.update_push();
        Ok(())
    }
}
