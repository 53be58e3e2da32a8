//! The GPU memory a scene allocates, computed without Vulkan (`hfgi plan` prints it and checks
//! it against a device's heaps before any work).
//!
//! [`renderer`] lists every buffer [`Renderer::new`] creates, [`view()`] / [`view_with`] every
//! image and buffer [`ViewPass::for_renderer`] creates, each under its debug name (the name
//! given to `Buffer::new` / `Image::new`) and in creation order. Every size comes from the
//! helpers the passes themselves size their buffers with (`PyramidBuffers`, `VisibilityData`
//! and `visibility::buffer_sizes`, `shade::upload_sizes`, `ScanData` and
//! `indirect::buffer_sizes`, `radiance::shape`, the max pyramid's layout, the view's
//! attachments and index size), so the two cannot drift apart; `tests/memory.rs` checks the
//! totals against `memory_bytes()` and the names against the allocator's live allocations.
//!
//! **Buffers** are counted in bytes as requested, which is what the passes' `memory_bytes()`
//! sum (`Buffer::size`): the totals are exact. **Images** (the view pass only) are counted as
//! `width · height · bytes per texel · samples`; `ViewPass::memory_bytes()` sums the driver's
//! `VkMemoryRequirements::size`, which a driver may pad (row alignment, tiling, compression
//! metadata). The colour format, depth format and sample count of the view images depend on
//! the device ([`crate::vk::graphics::choose_targets`]): [`view_with`] takes them, [`view()`]
//! assumes the largest the pass can pick.
//!
//! Not counted: the short-lived host-visible staging buffers of uploads and read-backs (one at
//! a time, the size of the data moved, freed before the call returns), pipelines and
//! descriptor pools, and the allocator's rounding of allocations into its memory blocks.
//!
//! [`Renderer::new`]: super::Renderer::new
//! [`ViewPass::for_renderer`]: super::view::ViewPass::for_renderer

use std::fmt;

use ash::vk;

use super::indirect::{self, ScanData};
use super::plan::Planner;
use super::pyramid::{buffer_name, PyramidBuffers, PyramidKind};
use super::pyramid_max::{self, uses_max_bound};
use super::radiance::{self, radiance_kind};
use super::renderer::vector_pyramid;
use super::shade;
use super::view::{self, CameraModel, ViewOptions, MAX_SAMPLES};
use super::visibility::{self, VisibilityData};
use crate::error::{Error, Result};
use crate::reference::max::MaxLayout;
use crate::scene::model::Scene;

/// Smallest buffer `Buffer::new` creates (smaller requests are rounded up to it).
const MIN_BUFFER_BYTES: u64 = 4;

/// The GPU buffers and images of a pass or of a renderer, in creation order.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MemoryEstimate {
    /// `(debug name, bytes)` of each buffer or image.
    pub buffers: Vec<(String, u64)>,
    /// `(debug name, owner's debug name)` of each buffer bound inside another's memory, which
    /// allocates nothing and is not in [`MemoryEstimate::buffers`] (`Buffer::aliasing`; docs/
    /// pyramid.md, "Shared levels").
    pub aliases: Vec<(String, String)>,
}

impl MemoryEstimate {
    /// Bytes of all entries.
    pub fn total(&self) -> u64 {
        self.buffers.iter().map(|(_, b)| b).sum()
    }

    /// Bytes of the exported shading planes (`hfgi.shade.output`: one RGB value per field texel
    /// and layer, docs/conventions.md). The rest of a renderer's estimate, `total() −
    /// exported_planes()`, is its inputs and intermediates: what the paper's table 1 counts.
    pub fn exported_planes(&self) -> u64 {
        self.buffers.iter().filter(|(n, _)| n == shade::OUTPUT_BUFFER).map(|(_, b)| b).sum()
    }

    /// The largest entry (the first of equals); `None` when empty.
    pub fn largest(&self) -> Option<&(String, u64)> {
        self.buffers.iter().rev().max_by_key(|(_, b)| *b)
    }

    /// Appends `other`'s entries (e.g. the view pass after the renderer).
    pub fn append(&mut self, other: MemoryEstimate) {
        self.buffers.extend(other.buffers);
        self.aliases.extend(other.aliases);
    }

    /// A buffer of `bytes` as requested from `Buffer::new` (which allocates at least 4 bytes).
    fn buffer(&mut self, name: impl Into<String>, bytes: u64) {
        self.buffers.push((name.into(), bytes.max(MIN_BUFFER_BYTES)));
    }

    fn buffers<N: Into<String>>(&mut self, list: impl IntoIterator<Item = (N, u64)>) {
        list.into_iter().for_each(|(n, b)| self.buffer(n, b));
    }
}

impl fmt::Display for MemoryEstimate {
    /// One line per entry (`name  bytes (MiB)`), then the total.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mib = |b: u64| b as f64 / 1048576.0;
        for (name, b) in &self.buffers {
            writeln!(f, "  {name:<28} {b:>14} B {:>10.2} MiB", mib(*b))?;
        }
        writeln!(f, "  {:<28} {:>14} B {:>10.2} MiB", "total", self.total(), mib(self.total()))
    }
}

/// What `Renderer::new(ctx, scene)` allocates and `Renderer::memory_bytes()` reports: the
/// height pyramid, the visibility and direct-shading passes and, when the planner creates it,
/// the indirect pass with its radiance pyramid and max pyramid. Fails where `Renderer::new`
/// fails before touching the GPU (invalid settings, sizes); the device's
/// `maxImageDimension2D` is not checked here.
pub fn renderer(scene: &Scene) -> Result<MemoryEstimate> {
    let gi = &scene.gi;
    gi.validate()?;
    let (w, h) = (scene.field.width(), scene.field.height());
    let work = gi.working_size(w, h);
    let n2 = gi.sh_order * gi.sh_order;
    let mut e = MemoryEstimate::default();
    let stack = Some(super::pyramid::height_stack_of(gi, w, h)?);
    let heights = PyramidBuffers::new(w, h, work, gi.level_step, gi.pyramid, PyramidKind::HEIGHTS, stack, None)?
        .with_tail(radiance::height_levels_tail(scene)?);
    e.buffers(heights.named(PyramidKind::HEIGHTS));
    let vis = VisibilityData::new(scene);
    e.buffers(visibility::buffer_sizes(vis.samples.len(), vis.fold.len(), vis.sets.len(), work, n2, gi.storage));
    if let Some(plan) = visibility::sweep_plan(scene) {
        e.buffers(plan.buffer_sizes());
    }
    e.buffers(super::blockers::buffer_sizes(scene));
    e.buffers(shade::upload_sizes(scene));
    e.buffer(shade::OUTPUT_BUFFER, shade::output_bytes(scene));
    e.buffer(shade::INCIDENT_BUFFER, shade::incident_bytes(scene));
    e.buffers(super::local::buffer_sizes(scene));
    if Planner::new(scene).creates_indirect() {
        e.append(indirect_pass(scene, work, heights.layout.count())?);
    }
    Ok(e)
}

/// The buffers of `IndirectPass::new`: its own, the radiance pyramid's and (with the bound)
/// the max pyramid's, for a height pyramid of `n_v` levels.
fn indirect_pass(scene: &Scene, work: (usize, usize), n_v: usize) -> Result<MemoryEstimate> {
    let gi = &scene.gi;
    let (w, h) = (scene.field.width(), scene.field.height());
    let mut e = MemoryEstimate::default();
    let scan = ScanData::new(scene, n_v);
    let work32 = (work.0 as u32, work.1 as u32);
    e.buffers(indirect::buffer_sizes(scene, work32, scan.samples.len(), scan.fold.len(), scan.ladder.len()));
    let n2 = (gi.sh_order * gi.sh_order) as u32;
    let (channels, mode) = radiance::shape(gi.pyramid, vector_pyramid(scene).then_some(n2));
    let kind = radiance_kind(channels, gi.storage);
    let planes = Some(indirect::radiance_stack_levels(&scan.radiance_levels(scene)?));
    let (bw, bh) = crate::rules::scene::radiance_base(scene);
    let mut rad = PyramidBuffers::new(bw, bh, work, gi.radiance_level_step, mode, kind, planes, None)?;
    // Levels kept in the height levels buffer (radiance::shares_height_levels) allocate nothing.
    if radiance::shares_height_levels(scene) {
        rad = rad.aliased();
        e.aliases.push((buffer_name(kind, "levels"), buffer_name(PyramidKind::HEIGHTS, "levels")));
    }
    e.buffers(rad.named(kind));
    if uses_max_bound(scene) {
        e.buffer(pyramid_max::BUFFER_NAME, pyramid_max::buffer_bytes(&MaxLayout::new(w, h)));
    }
    Ok(e)
}

/// The formats and sample count of the view pass's images (what
/// [`crate::vk::graphics::choose_targets`] picks on a device; `ViewPass::color_format`,
/// `depth_format` and `samples` report them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ViewTargets {
    pub color_format: vk::Format,
    pub depth_format: vk::Format,
    /// MSAA samples per pixel (a power of two).
    pub samples: u32,
}

impl ViewTargets {
    /// The largest targets the pass can pick for `opts`: `R32G32B32A32_SFLOAT`, `D32_SFLOAT` and
    /// the forced sample count or [`MAX_SAMPLES`]. A device picks these or smaller ones (a
    /// 16-bit colour format only where it multisamples higher, at most `MAX_SAMPLES`; a
    /// smaller depth format or fewer samples), so [`view()`] bounds the nominal sizes of any
    /// device's choice.
    pub fn largest(opts: &ViewOptions) -> Self {
        Self {
            color_format: view::COLOR_FORMATS[0],
            depth_format: crate::vk::graphics::DEPTH_FORMATS[0],
            samples: opts.samples.unwrap_or(MAX_SAMPLES),
        }
    }
}

/// [`view_with`] for [`ViewTargets::largest`]: without a device, the sample count (and so the
/// MSAA image) is the forced `opts.samples` or the pass's cap [`MAX_SAMPLES`]; a device that
/// supports fewer samples allocates less. For the exact figure of a device pass its choice to
/// [`view_with`].
pub fn view(scene: &Scene, opts: &ViewOptions) -> Result<MemoryEstimate> {
    view_with(scene, &ViewTargets::largest(opts))
}

/// What `ViewPass::for_renderer(ctx, scene, renderer, opts)` allocates on a device that picks
/// `targets`: the output, depth and (with more than one sample) MSAA images of the camera's
/// size, then the index buffer. Image sizes are nominal (see the module docs); the index
/// buffer is exact. Fails where the pass fails before touching the GPU (field size, camera).
pub fn view_with(scene: &Scene, targets: &ViewTargets) -> Result<MemoryEstimate> {
    let (w, h) = (scene.field.width(), scene.field.height());
    view::check_field_size(w, h)?;
    let (lo, hi) = scene.field.range();
    CameraModel::new(&scene.camera, w, h, scene.texel_size, f64::from(lo), f64::from(hi))?;
    if !targets.samples.is_power_of_two() {
        return Err(Error::param("view sample count", targets.samples, "a power of two (1, 2, 4, 8, …)"));
    }
    let pixels = u64::from(scene.camera.width) * u64::from(scene.camera.height);
    let mut e = MemoryEstimate::default();
    for a in view::attachments(targets.color_format, targets.depth_format, targets.samples) {
        e.buffers.push((a.name.to_string(), pixels * texel_bytes(a.format)? * u64::from(a.samples)));
    }
    e.buffer(view::INDEX_BUFFER, view::index_bytes(w));
    if scene.spheres.iter().any(view::sphere_is_live) {
        e.buffer(view::SPHERE_BUFFER, view::sphere_buffer_bytes(scene.spheres.len()));
        e.buffer(view::SPHERE_LIGHT_BUFFER, view::sphere_light_bytes(scene.key_lights.len()));
    }
    Ok(e)
}

/// Bytes per texel of the formats the view pass may pick.
fn texel_bytes(format: vk::Format) -> Result<u64> {
    match format {
        vk::Format::R32G32B32A32_SFLOAT => Ok(16),
        vk::Format::R16G16B16A16_SFLOAT => Ok(8),
        vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => Ok(4),
        vk::Format::D16_UNORM => Ok(2),
        other => Err(Error::param(
            "view image format",
            format!("{other:?}"),
            "one of view::COLOR_FORMATS or graphics::DEPTH_FORMATS",
        )),
    }
}

/// Name endings of the buffers read through texel views (checked against
/// `maxTexelBufferElements`): both pyramids' levels, tables, stacks and planes, the max
/// pyramid, the scans' samples, fold matrices, radiance-level ladder and swept horizons, `V`,
/// `U`, and the shading's light and triple table.
const TEXEL_VIEWED: [&str; 13] = [
    ".levels",
    ".table",
    ".stack",
    ".planes",
    ".max",
    ".samples",
    ".fold",
    ".radiance_level",
    ".horizons",
    "visibility.v",
    "indirect.u",
    ".light",
    ".triple",
];

/// `render`'s and `plan`'s checks of a scene against a device, before any GPU work (docs/
/// robustness.md, "Early, consistent checks"): the field within `maxImageDimension2D`, and the
/// renderer's and the view pass's memory ([`renderer`], [`view()`] with the default options)
/// within the device ([`check_fits`]), and with indirect light subgroup vote in compute shaders
/// (the indirect scan's walk, docs/performance.md §18). Returns the estimate.
pub fn check_device(scene: &Scene, info: &crate::vk::DeviceInfo) -> Result<MemoryEstimate> {
    let (w, h) = (scene.field.width(), scene.field.height());
    let max = info.max_image_dimension_2d;
    if w > max as usize || h > max as usize {
        return Err(Error::FieldSize {
            source_name: format!("{} on {}", "the scene", info.name),
            width: w,
            height: h,
            max,
        });
    }
    if Planner::new(scene).creates_indirect() {
        super::indirect::check_subgroup_vote(info)?;
    }
    let mut e = renderer(scene)?;
    e.append(view(scene, &ViewOptions::default())?);
    check_fits(&e, info)?;
    Ok(e)
}

/// `estimate` against `info`'s limits: no storage buffer above `maxStorageBufferRange` (the
/// view's images and index buffer are not storage buffers), no allocation above
/// `maxMemoryAllocationSize`, and the total within the largest device-local heap. The error
/// says what the scene needs, what the device has and how to need less.
pub fn check_fits(estimate: &MemoryEstimate, info: &crate::vk::DeviceInfo) -> Result<()> {
    let mib = |b: u64| format!("{:.1} MiB", b as f64 / 1048576.0);
    let how = "use gi.storage = \"f16\" (halves V, U and the radiance stack), gi.subsample = 2 or 4, fewer \
               gi.bounces, a lower gi.sh_order, a smaller field or camera";
    let storage = estimate.buffers.iter().filter(|(n, _)| !n.starts_with("hfgi.view."));
    if let Some((name, b)) = storage.clone().find(|(_, b)| *b > u64::from(info.max_storage_buffer_range)) {
        return Err(Error::param(
            format!("GPU buffer {name}"),
            mib(*b),
            format!(
                "at most {} (maxStorageBufferRange of {}); {how}",
                mib(u64::from(info.max_storage_buffer_range)),
                info.name
            ),
        ));
    }
    // The buffers the scanning passes read through texel views of 32-bit words (or of uvec4s,
    // fewer texels): `Buffer::with_texel_view`, docs/performance.md §17.
    let texel = |n: &str| TEXEL_VIEWED.iter().any(|t| n.ends_with(t));
    let max_texels = u64::from(info.max_texel_buffer_elements);
    if let Some((name, b)) = storage.clone().find(|(n, b)| texel(n) && *b / 4 > max_texels) {
        return Err(Error::param(
            format!("GPU buffer {name}"),
            format!("{} texels", b / 4),
            format!("at most {max_texels} (maxTexelBufferElements of {}); {how}", info.name),
        ));
    }
    let cap = info.max_memory_allocation_size;
    if let Some((name, b)) = estimate.buffers.iter().find(|(_, b)| cap > 0 && *b > cap) {
        return Err(Error::param(
            format!("GPU allocation {name}"),
            mib(*b),
            format!("at most {} (maxMemoryAllocationSize of {}); {how}", mib(cap), info.name),
        ));
    }
    let (total, heap) = (estimate.total(), info.device_local_heap_bytes);
    if heap > 0 && total > heap {
        let largest = estimate.largest().map(|(n, b)| format!("; largest {n} {}", mib(*b))).unwrap_or_default();
        return Err(Error::param(
            "GPU memory",
            format!("{}{largest}", mib(total)),
            format!("at most {} (the largest device-local heap of {}); {how}", mib(heap), info.name),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A device that can hold the scene but whose texel views cover fewer texels than the
    /// radiance levels hold: `check_fits` refuses it before any GPU work, naming the buffer and
    /// `maxTexelBufferElements`; with the limit one texel larger than the largest viewed buffer,
    /// it accepts.
    #[test]
    fn texel_views_beyond_the_device_limit_are_refused() {
        let scene = crate::scene::file::default_scene().expect("default scene");
        let e = renderer(&scene).expect("estimate");
        let viewed = |n: &str| TEXEL_VIEWED.iter().any(|t| n.ends_with(t));
        let largest = e.buffers.iter().filter(|(n, _)| viewed(n)).map(|(_, b)| *b / 4).max().expect("viewed");
        let mut info = crate::vk::DeviceInfo {
            max_texel_buffer_elements: (largest - 1) as u32,
            ..crate::vk::DeviceInfo::roomy_test_device()
        };
        let err = check_fits(&e, &info).expect_err("texel limit").to_string();
        assert!(err.contains("maxTexelBufferElements") && err.contains("hfgi."), "{err}");
        info.max_texel_buffer_elements = largest as u32;
        check_fits(&e, &info).expect("within the limit");
    }
}
