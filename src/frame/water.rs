//! Stage `water.step`: a water surface simulated on the GPU (course notes ch. 3 §3.7; the scheme,
//! its stability condition and the update contract are in `docs/dynamic.md`).
//!
//! The notes' membrane PDE `∂z/∂t = v, ∂v/∂t = c²∇²z` (z the displacement, v the velocity of a
//! lattice cell) is stepped explicitly on a `W × H` lattice. The state is `(z, v)` per texel
//! (interleaved `vec2`), in two storage buffers used as ping-pong: one step
//! ([`WaterSim::record_step`]) is one dispatch of `glsl/water/step.comp.glsl` that reads
//! `(z^n, v^n)` from one and writes `(z^{n+1}, v^{n+1})` to the other:
//!
//! ```text
//! v^{n+1} = (1 − δ)·v^n + k·L(z^n) + D^{n+1},   z^{n+1} = z^n + v^{n+1},   k = speed², δ = damping,
//! L(z)_ij = (z_{i−1,j} − z_ij) + (z_{i+1,j} − z_ij) + (z_{i,j−1} − z_ij) + (z_{i,j+1} − z_ij),
//! ```
//!
//! which, with `v^n = z^n − z^{n−1}`, is exactly the notes' two-level form (current and previous
//! height, fig. 26) `z^{n+1} = z^n + (1 − δ)(z^n − z^{n−1}) + k·L(z^n) + D` that the CPU twin
//! [`crate::reference::water`] runs. Stable for `0 < k < (2 − δ)/4`
//! ([`crate::scene::animated::max_stable_speed`], checked by [`WaterSim::new`]). The step also
//! writes `rest_level + scale·z^{n+1}` (f32, row-major, offset 0) into the caller's heights
//! buffer — normally [`crate::frame::Renderer::heights_buffer`]. Rain drops `D` come from
//! [`WaterParams::drops_at`] as push constants: nothing is uploaded per step.
//!
//! Synchronisation: the step begins with transfer→compute and compute→compute barriers (the
//! previous step's state writes, and earlier writers or readers of the heights buffer) and ends
//! with a compute→compute barrier, so a compute pass recorded after it (the pyramid) reads the
//! new heights. A transfer reader adds [`crate::vk::barrier::compute_to_transfer`].

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::shared::WaterPush;
use crate::error::{Error, Result};
use crate::scene::animated::{Boundary, WaterParams, MAX_DROPS_PER_STEP};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind, Recorder};

/// Stage name (timestamp scope and debug label).
pub const STAGE_STEP: &str = super::stages::stage_name("water.step");

/// Distinct heights buffers one simulation can write to (a descriptor-set pair is cached for
/// each).
pub const MAX_OUTPUTS: usize = 4;

/// The water simulation: state buffers, pipeline and step counter.
pub struct WaterSim {
    width: u32,
    height: u32,
    params: WaterParams,
    /// `state[cur]` holds `(z^n, v^n)` interleaved; the other one receives the next step.
    state: [Buffer; 2],
    cur: usize,
    pipeline: ComputePipeline,
    /// Per heights buffer (by handle): the set for `cur = 0` and the one for `cur = 1`.
    outputs: Vec<(vk::Buffer, [vk::DescriptorSet; 2])>,
    steps: u64,
}

impl WaterSim {
    /// Validates `params` (ranges and the stability condition), allocates the state for a
    /// `width × height` lattice and uploads `initial` (row-major displacements `z`, `W·H` finite
    /// values) as `z^0` with `v^0 = 0`: the surface starts at rest. One submit; waits for it.
    pub fn new(ctx: &Context, width: usize, height: usize, params: WaterParams, initial: &[f32]) -> Result<Self> {
        ctx.batched(|| Self::build(ctx, width, height, params, initial))
    }

    fn build(ctx: &Context, width: usize, height: usize, params: WaterParams, initial: &[f32]) -> Result<Self> {
        params.validate()?;
        let max = ctx.info().max_image_dimension_2d;
        if width < 2 || height < 2 || width > max as usize || height > max as usize {
            return Err(Error::FieldSize { source_name: "water simulation".into(), width, height, max });
        }
        if initial.len() != width * height {
            return Err(Error::param(
                "water initial state",
                format!("{} values", initial.len()),
                format!("{} values (a {width}×{height} lattice)", width * height),
            ));
        }
        if let Some(k) = initial.iter().position(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                source_name: "water initial state".into(),
                x: k % width,
                y: k / width,
                value: initial[k],
            });
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let bytes = (width * height * 8) as u64;
        let zv: Vec<f32> = initial.iter().flat_map(|&z| [z, 0.0]).collect();
        let a = Buffer::new(ctx, "hfgi.water.state0", bytes, usage, MemoryLocation::GpuOnly)?;
        let b = match Buffer::new(ctx, "hfgi.water.state1", bytes, usage, MemoryLocation::GpuOnly) {
            Ok(b) => b,
            Err(e) => {
                a.destroy(ctx);
                return Err(e);
            }
        };
        let made =
            memory::upload_f32(ctx, &a, 0, &zv).and_then(|_| memory::upload_f32(ctx, &b, 0, &zv)).and_then(|_| {
                ComputePipeline::new(
                    ctx,
                    &shaders::WATER_STEP_COMP,
                    &[DescriptorKind::StorageBuffer; 3],
                    std::mem::size_of::<WaterPush>() as u32,
                    &[],
                    2 * MAX_OUTPUTS as u32,
                )
            });
        match made {
            Ok(pipeline) => Ok(Self {
                width: width as u32,
                height: height as u32,
                params,
                state: [a, b],
                cur: 0,
                pipeline,
                outputs: Vec::new(),
                steps: 0,
            }),
            Err(e) => {
                a.destroy(ctx);
                b.destroy(ctx);
                Err(e)
            }
        }
    }

    /// The descriptor sets writing to `out`, allocated on first use.
    fn sets_for(&mut self, ctx: &Context, out: &Buffer) -> Result<[vk::DescriptorSet; 2]> {
        if let Some((_, sets)) = self.outputs.iter().find(|(b, _)| *b == out.raw) {
            return Ok(*sets);
        }
        if self.outputs.len() >= MAX_OUTPUTS {
            return Err(Error::param(
                "water heights buffers",
                format!("'{}' (a new buffer after {MAX_OUTPUTS})", out.name),
                format!("at most {MAX_OUTPUTS} distinct heights buffers per WaterSim"),
            ));
        }
        let [s0, s1] = &self.state;
        let sets = [
            self.pipeline.allocate_set(ctx, &[Bind::Buffer(s0), Bind::Buffer(s1), Bind::Buffer(out)])?,
            self.pipeline.allocate_set(ctx, &[Bind::Buffer(s1), Bind::Buffer(s0), Bind::Buffer(out)])?,
        ];
        self.outputs.push((out.raw, sets));
        Ok(sets)
    }

    /// Records one step into `rec` (scope [`STAGE_STEP`]) and writes the new heights
    /// `rest_level + scale·z` to `heights_out` (f32, row-major `W × H` from offset 0; storage
    /// usage, at least `4·W·H` bytes). Then a caller that renders calls
    /// [`crate::frame::Renderer::mark_heights_changed`] before [`crate::frame::Renderer::record`].
    ///
    /// `heights_out`'s descriptor sets are cached by handle, so it must stay alive as long as
    /// this simulation (the renderer's heights buffer does, when the renderer outlives it).
    /// Errors: a buffer too small, or more than [`MAX_OUTPUTS`] distinct buffers.
    pub fn record_step(&mut self, rec: &mut Recorder, heights_out: &Buffer) -> Result<()> {
        let need = u64::from(self.width) * u64::from(self.height) * 4;
        if heights_out.size < need {
            return Err(Error::param(
                format!("water heights buffer '{}' size", heights_out.name),
                format!("{} bytes", heights_out.size),
                format!("at least {need} bytes ({}×{} f32)", self.width, self.height),
            ));
        }
        let sets = self.sets_for(rec.ctx, heights_out)?;
        let step = self.steps + 1;
        let drops = self.params.drops_at(step, self.width as usize, self.height as usize);
        let mut push = WaterPush {
            width: self.width,
            height: self.height,
            wrap: (self.params.boundary == Boundary::Periodic) as u32,
            drop_count: drops.len().min(MAX_DROPS_PER_STEP) as u32,
            k: self.params.k() as f32,
            retain: (1.0 - self.params.damping) as f32,
            rest_level: self.params.rest_level as f32,
            scale: self.params.scale as f32,
            drops: [[0.0; 4]; 4],
        };
        for (slot, d) in push.drops.iter_mut().zip(&drops) {
            *slot = [d.x, d.y, d.amplitude, d.radius];
        }
        let set = sets[self.cur];
        let (w, h) = (self.width, self.height);
        let pipeline = &self.pipeline;
        rec.scope(STAGE_STEP, |ctx, cmd| {
            // The previous step's state writes (compute), and earlier writers or readers of the
            // heights buffer (an upload by transfer, the previous frame's pyramid by compute).
            barrier::transfer_to_compute(ctx, cmd);
            barrier::compute_to_compute(ctx, cmd);
            pipeline.dispatch(
                ctx,
                cmd,
                set,
                bytemuck::bytes_of(&push),
                [groups(w, crate::constants::WORKGROUP), groups(h, crate::constants::WORKGROUP), 1],
            );
            // The new heights and state, for the pyramid (or the next step).
            barrier::compute_to_compute(ctx, cmd);
        });
        self.cur = 1 - self.cur;
        self.steps = step;
        Ok(())
    }

    /// Steps recorded so far (the next step is number `steps() + 1` in the rain schedule).
    pub fn steps(&self) -> u64 {
        self.steps
    }

    pub fn params(&self) -> &WaterParams {
        &self.params
    }

    /// `(width, height)` of the lattice.
    pub fn size(&self) -> (usize, usize) {
        (self.width as usize, self.height as usize)
    }

    /// Reads the current displacement `z^n` back (waits; call after the steps' submission
    /// completed). For tests and tools.
    pub fn read_displacement(&self, ctx: &Context) -> Result<Vec<f32>> {
        Ok(self.read_state(ctx)?.into_iter().map(|[z, _]| z).collect())
    }

    /// Reads the current state `(z^n, v^n)` per texel back (waits), `v^n = z^n − z^{n−1}`.
    pub fn read_state(&self, ctx: &Context) -> Result<Vec<[f32; 2]>> {
        let n = u64::from(self.width) * u64::from(self.height);
        let flat = memory::download_f32(ctx, &self.state[self.cur], 0, 2 * n)?;
        Ok(flat.chunks_exact(2).map(|c| [c[0], c[1]]).collect())
    }

    /// GPU memory held by the state buffers, in bytes.
    pub fn memory_bytes(&self) -> u64 {
        self.state[0].size + self.state[1].size
    }

    /// Frees the buffers and the pipeline (and so the cached descriptor sets).
    pub fn destroy(mut self, ctx: &Context) {
        self.pipeline.destroy(ctx);
        let [a, b] = self.state;
        a.destroy(ctx);
        b.destroy(ctx);
    }
}
