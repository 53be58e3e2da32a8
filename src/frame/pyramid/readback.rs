//! Read-backs of a [`HeightPyramid`]'s buffers and the GPU probe of its lookups, for tests,
//! pictures and diagnostics (each waits for the device).

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{HeightPyramid, PUSH_SIZE};
use crate::error::{Error, Result};
use crate::frame::shared::PyramidPush;
use crate::frame::storage::download_vectors;
use crate::scene::model::{PyramidMode, Storage};
use crate::shaders;
use crate::vk::pipeline::{groups, Bind};
use crate::vk::{barrier, memory, Buffer, ComputePipeline, Context, DescriptorKind};

impl HeightPyramid {
    /// Reads level `i` back (waits). For tests and pictures. Level 0 holds what was written
    /// (absolute heights); levels ≥ 1 hold values relative to [`HeightPyramid::origin`].
    pub fn read_level(&self, ctx: &Context, i: usize) -> Result<Vec<f32>> {
        let l =
            *self.layout.levels.get(i).ok_or_else(|| Error::param("level", i, format!("< {}", self.layout.count())))?;
        memory::download_f32(ctx, &self.levels, l.offset as u64, (l.width * l.height) as u64)
    }

    /// Reads stack plane `i` back (waits; relative to [`HeightPyramid::origin`]). Stack mode only.
    pub fn read_stack(&self, ctx: &Context, i: usize) -> Result<Vec<f32>> {
        let s = self.stack.as_ref().ok_or_else(|| Error::param("read_stack", "pyramid mode", "stack mode"))?;
        if self.kind.stack_storage != Storage::F32 {
            return Err(Error::param("read_stack", "an f16 stack", "an f32 stack (read_stack_all reads any)"));
        }
        if i >= self.stack_levels {
            return Err(Error::param(
                "stack level",
                i,
                format!("< {} (the levels the stack holds)", self.stack_levels),
            ));
        }
        let [w, h, offset, _] = self.plane_table[i];
        memory::download_f32(ctx, s, u64::from(offset), u64::from(w) * u64::from(h))
    }

    /// Diagnostics: the whole levels buffer (every channel, [`PyramidLayout`] order; channel
    /// `c` starts at float `c·total`), read back (waits). Call after a recorded frame completed.
    pub fn read_levels_all(&self, ctx: &Context) -> Result<Vec<f32>> {
        memory::download_f32(ctx, &self.levels, 0, self.layout.total * u64::from(self.kind.channels.max(1)))
    }

    /// Diagnostics: the whole stack buffer (`channels · stack_levels()` planes laid out as
    /// [`HeightPyramid::stack_planes_buffer`] says, padding included), read back (waits); `None`
    /// in pyramid mode. Call after a recorded frame completed.
    pub fn read_stack_all(&self, ctx: &Context) -> Result<Option<Vec<f32>>> {
        let stride = self.plane_table.last().map_or(0, |p| p[2] as usize);
        let values = self.kind.channels.max(1) as usize * stride;
        let storage = self.kind.stack_storage;
        let read = self.stack.as_ref().map(|s| download_vectors(ctx, s, storage, 0, 1, values));
        let unexpose = 1.0 / self.stack_scale;
        Ok(read.transpose()?.map(|v| v.into_iter().map(|x| x * unexpose).collect()))
    }

    /// Samples the pyramid at `(level, x, y)` queries (x, y in level-0 texel units) on the GPU
    /// exactly as the scanning passes do: bilinear on the stack, or B-spline on the fly. The
    /// values are relative to [`HeightPyramid::origin`] (absolute with the default origin 0).
    /// In stack mode a query's level must be one the stack holds (`< stack_levels()`).
    pub fn probe(&self, ctx: &Context, queries: &[[f32; 3]]) -> Result<Vec<f32>> {
        let top = if self.stack.is_some() { self.stack_levels } else { self.layout.count() };
        if let Some(q) = queries.iter().find(|q| !(q[0] >= 0.0 && (q[0] as usize) < top)) {
            return Err(Error::param("probe level", q[0], format!("0 ≤ level < {top}")));
        }
        let q: Vec<[f32; 4]> = queries.iter().map(|q| [q[0], q[1], q[2], 0.0]).collect();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let qb = Buffer::new(ctx, "hfgi.pyramid.probe.queries", (q.len() * 16) as u64, usage, MemoryLocation::GpuOnly)?;
        let rb =
            match Buffer::new(ctx, "hfgi.pyramid.probe.result", (q.len() * 4) as u64, usage, MemoryLocation::GpuOnly) {
                Ok(b) => b,
                Err(e) => {
                    qb.destroy(ctx);
                    return Err(e);
                }
            };
        let mut pipe: Option<ComputePipeline> = None;
        let r = (|| -> Result<Vec<f32>> {
            memory::upload(ctx, &qb, 0, bytemuck::cast_slice(&q))?;
            let p = pipe.insert(ComputePipeline::new(
                ctx,
                &shaders::PYRAMID_PROBE_COMP,
                &[DescriptorKind::StorageBuffer; 6],
                PUSH_SIZE,
                &[],
                1,
            )?);
            let stack = self.stack.as_ref().unwrap_or(&self.levels);
            let set = p.allocate_set(
                ctx,
                &[
                    Bind::Buffer(&self.levels),
                    Bind::Buffer(&self.table),
                    Bind::Buffer(stack),
                    Bind::Buffer(&qb),
                    Bind::Buffer(&rb),
                    Bind::Buffer(self.height_planes()),
                ],
            )?;
            let push = PyramidPush {
                level: (self.mode == PyramidMode::Pyramid) as u32,
                wrap: self.wrap as u32,
                out_width: self.work.0,
                out_height: self.work.1,
                scale: 1.0,
                flags: 0,
            };
            ctx.submit_and_wait(|cmd| {
                barrier::compute_to_compute(ctx, cmd);
                p.dispatch(
                    ctx,
                    cmd,
                    set,
                    bytemuck::bytes_of(&push),
                    [groups(q.len() as u32, crate::constants::WORKGROUP_1D), 1, 1],
                );
                Ok(())
            })?;
            memory::download_f32(ctx, &rb, 0, q.len() as u64)
        })();
        if let Some(mut p) = pipe {
            p.destroy(ctx);
        }
        qb.destroy(ctx);
        rb.destroy(ctx);
        r
    }
}
