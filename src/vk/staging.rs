//! A host-visible staging ring that the host sizes, for the recorded uploads and read-backs
//! (`Renderer::record_heights_upload`, `Renderer::record_read_layers`; docs/integration.md §3).
//!
//! hfgi writes into (or reads from) the ring's mapped memory on the CPU and records the copies
//! into the caller's command buffer; it never submits or waits. The host calls
//! [`StagingRing::reset`] once the GPU has finished every command that used the ring (its own
//! fence): one ring per frame in flight.

use ash::vk;
use gpu_allocator::MemoryLocation;

use super::{Buffer, Context};
use crate::error::{Error, Result};

/// Which way a ring moves data.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RingKind {
    /// Host → GPU (`CpuToGpu` memory, `TRANSFER_SRC`).
    Upload,
    /// GPU → host (`GpuToCpu` memory, `TRANSFER_DST`).
    Readback,
}

/// Offsets within the ring are multiples of this.
const ALIGN: u64 = 16;

/// A host-visible buffer handed out front to back until [`StagingRing::reset`].
pub struct StagingRing {
    buffer: Buffer,
    head: u64,
    kind: RingKind,
}

impl StagingRing {
    /// A ring of `bytes` (one GPU allocation, named `name`).
    pub fn new(ctx: &Context, name: &str, bytes: u64, kind: RingKind) -> Result<Self> {
        let (usage, location) = match kind {
            RingKind::Upload => (vk::BufferUsageFlags::TRANSFER_SRC, MemoryLocation::CpuToGpu),
            RingKind::Readback => (vk::BufferUsageFlags::TRANSFER_DST, MemoryLocation::GpuToCpu),
        };
        Ok(Self { buffer: Buffer::new(ctx, name, bytes, usage, location)?, head: 0, kind })
    }

    /// Makes the whole ring free again. Call it only after the GPU has finished every command
    /// recorded with it (and, for a read-back ring, after reading what they wrote).
    pub fn reset(&mut self) {
        self.head = 0;
    }

    /// Bytes handed out since the last [`StagingRing::reset`].
    pub fn used(&self) -> u64 {
        self.head
    }

    pub fn capacity(&self) -> u64 {
        self.buffer.size
    }

    pub fn kind(&self) -> RingKind {
        self.kind
    }

    /// The ring's buffer (for the host's own copies).
    pub fn buffer(&self) -> &Buffer {
        &self.buffer
    }

    /// Reserves `len` bytes; returns their offset.
    pub fn reserve(&mut self, len: u64) -> Result<u64> {
        let offset = self.head.div_ceil(ALIGN) * ALIGN;
        if offset + len > self.buffer.size {
            return Err(Error::param(
                format!("staging ring '{}'", self.buffer.name),
                format!("{len} more bytes with {offset} of {} in use", self.buffer.size),
                "room for them: reset() the ring once the GPU finished the frames that used it, or create a larger \
                 ring",
            ));
        }
        self.head = offset + len;
        Ok(offset)
    }

    /// Copies `data` into the ring (an upload ring); returns its offset.
    pub fn push(&mut self, data: &[u8]) -> Result<u64> {
        self.expect(RingKind::Upload)?;
        let offset = self.reserve(data.len() as u64)?;
        let at = offset as usize;
        self.buffer.mapped()?[at..at + data.len()].copy_from_slice(data);
        Ok(offset)
    }

    /// The `len` bytes at `offset` of a read-back ring (valid once the GPU finished the copy
    /// into them and the host waited for it).
    pub fn read(&mut self, offset: u64, len: u64) -> Result<&[u8]> {
        self.expect(RingKind::Readback)?;
        if offset + len > self.buffer.size {
            return Err(Error::param("staging ring read", format!("{len} bytes at {offset}"), "within the ring"));
        }
        let m = self.buffer.mapped()?;
        Ok(&m[offset as usize..(offset + len) as usize])
    }

    fn expect(&self, kind: RingKind) -> Result<()> {
        if self.kind == kind {
            Ok(())
        } else {
            Err(Error::param(
                format!("staging ring '{}'", self.buffer.name),
                format!("{:?}", self.kind),
                format!("a {kind:?} ring"),
            ))
        }
    }

    pub fn destroy(self, ctx: &Context) {
        self.buffer.destroy(ctx);
    }
}
