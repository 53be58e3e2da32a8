//! Live inputs (docs/integration.md §2): the lights, the material and the shading camera change
//! between frames through [`Renderer::set_environment`], [`Renderer::set_key_lights`],
//! [`Renderer::set_material`] and [`Renderer::set_camera`], without a new `Renderer`, a
//! pipeline, a submit or a wait.
//!
//! A setter checks its input (typed errors naming the value), computes the new buffer data on
//! the CPU (f64, as at creation) and the push constants, and marks what is out of date. The
//! next [`Renderer::record`] records, into the caller's command buffer, stage `inputs.update`
//! (a barrier after earlier reads, `vkCmdUpdateBuffer` of each changed range, a barrier before
//! the compute reads) and then the stages the plan asks for (docs/plan.md §1).
//!
//! What is fixed at creation: the number of key-light slots ([`RendererOptions::key_lights`];
//! unused slots hold a dark light), whether there is an environment set (a renderer created
//! with an all-zero environment has none), the albedo map, and the material's structure
//! (whether the surface reflects light at all, which creates the indirect pass, and the
//! glossy vector pyramid).

use ash::vk;
use glam::DVec3;

use super::plan::{Changes, Pending, Stage};
use super::renderer::{needs_indirect, vector_pyramid, Renderer};
use super::shade::{self, light_data};
use super::visibility::{SetKind, VisibilityData};
use crate::error::{Error, Result};
use crate::math::triple;
use crate::rules::lighting::light_sets_with;
use crate::scene::model::{Albedo, Camera, Environment, KeyLight, LocalLight, Material, Scene, SphereBlocker};
use crate::vk::{barrier, Recorder};

/// Largest data one `vkCmdUpdateBuffer` may write (Vulkan: 65536 bytes).
const UPDATE_CHUNK: usize = 65536;

/// Creation options of a [`Renderer`] beyond the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RendererOptions {
    /// Key-light slots: the most key lights [`Renderer::set_key_lights`] accepts (default and
    /// minimum: the scene's count). Each slot is a light set (visibility `m_k` azimuths).
    pub key_lights: Option<usize>,
    /// Local-light slots: the most local lights [`Renderer::set_local_lights`] accepts
    /// (default and minimum: the scene's count; 0 creates no local-light pass).
    pub local_lights: Option<usize>,
    /// Sphere-blocker slots: the most spheres [`Renderer::set_spheres`] accepts (default and
    /// minimum: the scene's count; 0 creates no blocker pass).
    pub spheres: Option<usize>,
}

/// A sphere slot without a sphere: one texel wide, far below any surface and culled there
/// (below every receiver's tangent plane).
pub fn dark_sphere(texel_size: f64) -> SphereBlocker {
    SphereBlocker {
        center: DVec3::new(0.0, 0.0, -crate::scene::model::limits::MAX_COORDINATE),
        radius: texel_size,
        albedo: [0.0; 3],
    }
}

/// A local-light slot without a light: no radiance (the shader skips it).
pub fn dark_local_light(texel_size: f64) -> LocalLight {
    LocalLight { position: DVec3::ZERO, radius: texel_size, radiance: [0.0; 3] }
}

/// A slot without a light: no radiance, pointing up (its visibility is computed and multiplied
/// by zero).
pub fn dark_key_light() -> KeyLight {
    KeyLight { direction: DVec3::Z, angular_radius: 1f64.to_radians(), radiance: [0.0; 3] }
}

/// `scene` with its key lights padded with [`dark_key_light`] to `opts.key_lights` slots.
pub fn with_slots(scene: &Scene, opts: &RendererOptions) -> Result<Scene> {
    let slots = opts.key_lights.unwrap_or(scene.key_lights.len());
    if slots < scene.key_lights.len() {
        return Err(Error::param(
            "RendererOptions::key_lights",
            slots,
            format!("at least the scene's {} key lights", scene.key_lights.len()),
        ));
    }
    if slots > MAX_KEY_LIGHTS {
        return Err(Error::param("RendererOptions::key_lights", slots, format!("at most {MAX_KEY_LIGHTS}")));
    }
    let mut s = scene.clone();
    s.key_lights.resize(slots, dark_key_light());
    let local = opts.local_lights.unwrap_or(scene.local_lights.len());
    if local < scene.local_lights.len() || local > MAX_LOCAL_LIGHTS {
        return Err(Error::param(
            "RendererOptions::local_lights",
            local,
            format!("at least the scene's {} local lights and at most {MAX_LOCAL_LIGHTS}", scene.local_lights.len()),
        ));
    }
    s.local_lights.resize(local, dark_local_light(scene.texel_size));
    let spheres = opts.spheres.unwrap_or(scene.spheres.len());
    if spheres < scene.spheres.len() || spheres > MAX_SPHERES {
        return Err(Error::param(
            "RendererOptions::spheres",
            spheres,
            format!("at least the scene's {} spheres and at most {MAX_SPHERES}", scene.spheres.len()),
        ));
    }
    s.spheres.resize(spheres, dark_sphere(scene.texel_size));
    Ok(s)
}

/// Most sphere-blocker slots.
pub const MAX_SPHERES: usize = 1024;

/// Most local-light slots (each costs its horizon marches at every texel).
pub const MAX_LOCAL_LIGHTS: usize = 256;

/// Most key-light slots (each is a visibility set of the shading's loop).
pub const MAX_KEY_LIGHTS: usize = 64;

/// One `vkCmdUpdateBuffer` range.
pub(crate) struct Update {
    dst: vk::Buffer,
    offset: u64,
    data: Vec<u8>,
}

/// The live state of a renderer: the scene as last set (its heights are those given at
/// creation and not used after it), the updates to record and the work left out of date.
pub(crate) struct Live {
    pub(crate) scene: Scene,
    updates: Vec<Update>,
    pub(crate) pending: Pending,
    triple_count: u32,
    indirect: bool,
}

impl Live {
    pub(crate) fn new(scene: Scene) -> Self {
        let triple_count = triple::triple(scene.gi.sh_order).entries.len() as u32;
        let indirect = needs_indirect(&scene);
        Self { scene, updates: Vec::new(), pending: Pending::default(), triple_count, indirect }
    }

    /// Queues `data` for `dst` at `offset`, replacing an earlier update of the same range.
    fn update(&mut self, dst: vk::Buffer, offset: u64, data: Vec<u8>) {
        self.updates.retain(|u| !(u.dst == dst && u.offset == offset));
        self.updates.push(Update { dst, offset, data });
        self.pending.upload_bytes = self.updates.iter().map(|u| u.data.len() as u64).sum();
    }

    fn changed(&mut self, what: Changes) {
        self.pending.direct |= what;
        if self.indirect {
            self.pending.indirect |= what;
        }
    }

    /// After a recorded frame of `stages`: what it did is no longer pending.
    pub(crate) fn recorded(&mut self, stages: &[Stage]) {
        let has = |s: Stage| stages.contains(&s);
        self.updates.clear();
        self.pending.upload_bytes = 0;
        if has(Stage::VisibilityKeyLights) {
            self.pending.key_lights_moved = false;
        }
        if has(Stage::VisibilityBlockers) {
            self.pending.spheres_moved = false;
        }
        let (direct, indirect) = (has(Stage::ShadeDirect), has(Stage::IndirectShade(1)));
        if direct {
            self.pending.direct = Changes::NONE;
        }
        if indirect {
            self.pending.indirect = Changes::NONE;
        } else if direct && self.indirect {
            // The bounces read the direct light just re-shaded.
            self.pending.indirect |= Changes::DIRECT_LIGHT;
        }
    }
}

/// Records stage `inputs.update` (nothing when no update is queued).
pub(crate) fn record_updates(live: &Live, rec: &mut Recorder) {
    if live.updates.is_empty() {
        return;
    }
    rec.scope(Stage::InputsUpdate.name(), |ctx, cmd| {
        barrier::compute_to_update(ctx, cmd);
        for u in &live.updates {
            for (i, chunk) in u.data.chunks(UPDATE_CHUNK).enumerate() {
                let offset = u.offset + (i * UPDATE_CHUNK) as u64;
                unsafe { ctx.device().cmd_update_buffer(cmd, u.dst, offset, chunk) };
            }
        }
        barrier::update_to_compute(ctx, cmd);
    });
}

impl Renderer {
    /// Sets the environment light (SH coefficients, already rotated and scaled: see
    /// [`Environment::rotated`], [`Environment::scaled`]). Takes effect at the next
    /// [`Renderer::record`], which re-shades without recomputing any visibility.
    pub fn set_environment(&mut self, environment: &Environment) -> Result<()> {
        environment.check()?;
        let kinds = self.visibility.set_kinds();
        if !kinds.contains(&SetKind::Environment) && environment.sh.iter().any(|c| c.iter().any(|v| *v != 0.0)) {
            return Err(Error::param(
                "environment",
                "non-zero SH coefficients",
                "all zero: this renderer was created with a black environment and has no environment light set \
                 (create it with a non-zero environment)",
            ));
        }
        self.live.scene.environment = environment.clone();
        self.queue_lighting();
        self.live.changed(Changes::ENVIRONMENT);
        self.refresh_pre_exposure();
        Ok(())
    }

    /// Sets the key lights: at most the renderer's slots ([`RendererOptions::key_lights`]);
    /// the slots left over hold no light. Moved or resized lights re-run
    /// `visibility.key_lights` at the next [`Renderer::record`]; a change of radiance only
    /// re-shades.
    pub fn set_key_lights(&mut self, lights: &[KeyLight]) -> Result<()> {
        let slots = self.live.scene.key_lights.len();
        if lights.len() > slots {
            return Err(Error::param(
                "key lights",
                lights.len(),
                format!("at most {slots} (the key-light slots fixed at creation: RendererOptions::key_lights)"),
            ));
        }
        for (k, l) in lights.iter().enumerate() {
            l.check(k)?;
        }
        let mut next: Vec<KeyLight> = lights.to_vec();
        next.resize(slots, dark_key_light());
        let moved = next
            .iter()
            .zip(&self.live.scene.key_lights)
            .any(|(a, b)| a.direction != b.direction || a.angular_radius != b.angular_radius);
        self.live.scene.key_lights = next;
        if moved {
            let keys: Vec<_> = self.live_sets().into_iter().filter(|(k, _)| *k != SetKind::Environment).collect();
            let data = VisibilityData::for_sets(&self.live.scene, &keys);
            for (dst, offset, bytes) in self.visibility.key_light_updates(&data) {
                self.live.update(dst, offset, bytes);
            }
            self.live.pending.key_lights_moved = true;
        }
        self.queue_lighting();
        self.live.changed(Changes::KEY_LIGHTS);
        self.refresh_pre_exposure();
        Ok(())
    }

    /// Sets the local lights: at most the renderer's slots ([`RendererOptions::local_lights`]);
    /// the slots left over hold no light. Any change re-runs `shade.direct` and
    /// `shade.local_lights` (and the bounces) at the next [`Renderer::record`]; no visibility
    /// set is recomputed (the local lights' horizons are marched inside their stage).
    pub fn set_local_lights(&mut self, lights: &[LocalLight]) -> Result<()> {
        let slots = self.live.scene.local_lights.len();
        let Some(pass) = self.local.as_ref().filter(|_| lights.len() <= slots) else {
            return Err(Error::param(
                "local lights",
                lights.len(),
                format!("at most {slots} (the local-light slots fixed at creation: RendererOptions::local_lights)"),
            ));
        };
        let s = self.live.scene.texel_size;
        for (k, l) in lights.iter().enumerate() {
            l.check(k, s)?;
        }
        let mut next: Vec<LocalLight> = lights.to_vec();
        next.resize(slots, dark_local_light(s));
        let (dst, offset, bytes) = pass.light_update(&next);
        self.live.update(dst, offset, bytes);
        self.live.scene.local_lights = next;
        self.live.changed(Changes::LOCAL_LIGHTS);
        self.refresh_pre_exposure();
        Ok(())
    }

    /// Sets the sphere blockers: at most the renderer's slots ([`RendererOptions::spheres`]);
    /// the slots left over hold no sphere. A change re-runs `visibility.blockers` and the
    /// shading (direct and bounces) at the next [`Renderer::record`].
    pub fn set_spheres(&mut self, spheres: &[SphereBlocker]) -> Result<()> {
        let slots = self.live.scene.spheres.len();
        let Some(pass) = self.blockers.as_ref().filter(|_| spheres.len() <= slots) else {
            return Err(Error::param(
                "spheres",
                spheres.len(),
                format!("at most {slots} (the sphere slots fixed at creation: RendererOptions::spheres)"),
            ));
        };
        let s = self.live.scene.texel_size;
        for (k, b) in spheres.iter().enumerate() {
            b.check(k, s)?;
        }
        let mut next: Vec<SphereBlocker> = spheres.to_vec();
        next.resize(slots, dark_sphere(s));
        let (dst, offset, bytes) = pass.sphere_update(&next);
        self.live.update(dst, offset, bytes);
        self.live.scene.spheres = next;
        self.live.pending.spheres_moved = true;
        self.live.changed(Changes::SPHERES);
        Ok(())
    }

    /// Sets the material: a constant albedo, the Phong specular colour and exponent. Fixed at
    /// creation: an albedo map (pass it unchanged), whether the surface has a specular colour
    /// (the shading buffer's glossy planes: create it with `specular = Some([0.0; 3])` to turn
    /// the gloss on later), and whether it reflects light and uses the glossy vector pyramid
    /// (the passes created for it).
    pub fn set_material(&mut self, material: &Material) -> Result<()> {
        material.check()?;
        let old = &self.live.scene;
        match (&old.material.albedo, &material.albedo) {
            (Albedo::Constant(_), Albedo::Constant(_)) => {}
            (Albedo::Map(a), Albedo::Map(b)) if a == b => {}
            _ => {
                return Err(Error::param(
                    "material albedo",
                    "a different albedo map, or a map instead of a constant (or back)",
                    "the albedo map fixed at creation, or a constant albedo when created with one",
                ))
            }
        }
        let mut next = old.clone();
        next.material = material.clone();
        for (what, before, after) in [
            ("reflects light (the indirect pass)", needs_indirect(old), needs_indirect(&next)),
            (
                "has a specular colour (the shading buffer's glossy planes)",
                shade::glossy_planes(old),
                shade::glossy_planes(&next),
            ),
            ("uses the glossy vector pyramid", vector_pyramid(old), vector_pyramid(&next)),
        ] {
            if before != after {
                return Err(Error::param(
                    "material",
                    format!("a surface that {}{what}", if after { "" } else { "no longer " }),
                    format!(
                        "the structure fixed at creation (the surface {}{what})",
                        if before { "" } else { "never " }
                    ),
                ));
            }
        }
        let exponent_changed = material.exponent != old.material.exponent;
        if exponent_changed {
            let consts = shade::constants(
                old.gi.sh_order,
                old.gi.diffuse_lobe,
                f64::from(material.exponent),
                self.live.triple_count,
            );
            let dst = self.shade.bindings()[3].raw;
            self.live.update(dst, 0, bytemuck::cast_slice(&consts).to_vec());
        }
        self.live.scene.material = material.clone();
        self.shade.push_mut().set_material(material);
        if let Some(b) = self.blockers.as_mut().filter(|b| exponent_changed && b.view_dependent()) {
            // log_brdf: the glossy transfer's Phong lobe (docs/blockers.md §3).
            b.set_view(self.live.scene.camera.position, f64::from(material.exponent));
            self.live.pending.spheres_moved = true;
        }
        if let Some(l) = self.local.as_mut() {
            l.push_mut().set_material(material);
        }
        let spec = material.specular.unwrap_or([0.0; 3]);
        if let Some(i) = self.indirect.as_mut() {
            i.update_pushes(|p| p.set_material(material), spec);
        }
        self.live.changed(Changes::MATERIAL);
        self.refresh_pre_exposure();
        Ok(())
    }

    /// Sets the shading camera (the view vector of the glossy lobe; `ViewPass::set_camera`
    /// moves the view image's camera). Re-shades only a glossy surface: diffuse light does not
    /// depend on the viewer.
    pub fn set_camera(&mut self, camera: &Camera) -> Result<()> {
        camera.check()?;
        self.live.scene.camera = camera.clone();
        self.shade.push_mut().set_camera(camera.position);
        if let Some(l) = self.local.as_mut() {
            l.push_mut().set_camera(camera.position);
        }
        let spec = self.live.scene.material.specular.unwrap_or([0.0; 3]);
        if let Some(b) = self.blockers.as_mut().filter(|b| b.view_dependent()) {
            // log_brdf: the glossy transfer's view vector (docs/blockers.md §3).
            b.set_view(camera.position, f64::from(self.live.scene.material.exponent));
            if spec.iter().any(|v| *v != 0.0) {
                self.live.pending.spheres_moved = true;
            }
        }
        if let Some(i) = self.indirect.as_mut() {
            i.update_pushes(|p| p.set_camera(camera.position), spec);
        }
        if spec.iter().any(|v| *v != 0.0) {
            self.live.changed(Changes::CAMERA);
        }
        Ok(())
    }

    /// The pre-exposure of f16 storage follows the live lights and material
    /// ([`super::storage::pre_exposure`]; the next recorded bounces use it).
    fn refresh_pre_exposure(&mut self) {
        let scale = super::storage::pre_exposure(&self.live.scene);
        if let Some(i) = self.indirect.as_mut() {
            i.set_pre_exposure(scale);
        }
    }

    /// The lights, material and camera as last set (the scene given at creation, with its key
    /// lights padded to the slots, then every `set_*`).
    pub fn live_scene(&self) -> &Scene {
        &self.live.scene
    }

    /// The live scene's light sets in the renderer's order (the sets fixed at creation).
    fn live_sets(&self) -> Vec<(SetKind, crate::math::azimuth::AzimuthSet)> {
        light_sets_with(&self.live.scene, self.visibility.set_kinds().contains(&SetKind::Environment))
    }

    /// Queues `hfgi.shade.light` from the live lights, in the renderer's set order.
    fn queue_lighting(&mut self) {
        let data = light_data(&self.live.scene, &self.live_sets());
        let dst = self.shade.bindings()[0].raw;
        self.live.update(dst, 0, bytemuck::cast_slice(&data).to_vec());
    }
}
