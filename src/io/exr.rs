//! OpenEXR output of per-texel values (shading textures, height fields) and a reader for tests.
//!
//! Layers follow the OpenEXR naming convention for layers within one part (the
//! "Technical Introduction to OpenEXR", *Layers*): a channel `C` of layer `L` is stored as the
//! channel named `L.C`, and the default layer's channels have no prefix. So a file written with
//! layers `""`, `direct` and `indirect` holds the channels `B, G, R, direct.B, direct.G,
//! direct.R, indirect.B, …` in one scan-line part, which `exrheader`, `oiiotool`, Nuke and
//! Blender all list as the layers `direct` and `indirect` beside the default RGB. (The `exr`
//! crate's own "layers" are multi-part files, which older tools do not understand and which
//! cannot hold an unnamed default layer, so they are not used for writing;
//! [`read_layers`] reads both.)
//!
//! Samples are float32, ZIP-compressed (lossless), line order increasing: row 0 of the data
//! (`j = 0`) is the top row of the image.

use std::collections::BTreeSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use exr::prelude::*;

use crate::error::{Error, Result};

/// One layer to write: named channels of `width·height` row-major float32 samples.
#[derive(Clone, Debug)]
pub struct Layer<'a> {
    /// Layer name; `""` is the default layer (channels stored without a prefix). Must not
    /// start or end with `.`.
    pub name: &'a str,
    /// `(channel name, samples)`, e.g. `("R", &red)`. Channel names must be non-empty.
    pub channels: Vec<(&'a str, &'a [f32])>,
}

/// Writes `layers` to the OpenEXR file `path` as float32 channels named `layer.channel` (plain
/// `channel` for the default layer `""`), see the module docs.
///
/// Errors: [`Error::InvalidParameter`] for a zero size, no channels, an empty or duplicate
/// full channel name, or a channel whose length is not `width·height`; [`Error::Io`] /
/// [`Error::Format`] if writing fails.
pub fn write_layers(path: &Path, width: usize, height: usize, layers: &[Layer<'_>]) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::param(
            format!("{}: image size", path.display()),
            format!("{width}×{height}"),
            "at least 1×1",
        ));
    }
    let n = width
        .checked_mul(height)
        .ok_or_else(|| Error::param("EXR size", format!("{width}×{height}"), "a size that fits in memory"))?;
    let mut names = BTreeSet::new();
    let mut list = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for layer in layers {
        if layer.name.starts_with('.') || layer.name.ends_with('.') {
            return Err(Error::param(
                "EXR layer name",
                format!("'{}'", layer.name),
                "a name not starting or ending with '.'",
            ));
        }
        for &(channel, data) in &layer.channels {
            let full = if layer.name.is_empty() { channel.to_string() } else { format!("{}.{channel}", layer.name) };
            if channel.is_empty() {
                return Err(Error::param("EXR channel name", format!("'{full}'"), "a non-empty channel name"));
            }
            if data.len() != n {
                return Err(Error::param(
                    format!("EXR channel '{full}' length"),
                    data.len(),
                    format!("{n} samples for {width}×{height}"),
                ));
            }
            let text = Text::new_or_none(full.as_str()).ok_or_else(|| {
                Error::param("EXR channel name", format!("'{full}'"), "1 to 255 bytes of Latin-1 text")
            })?;
            if !names.insert(full.clone()) {
                return Err(Error::param("EXR channel name", format!("'{full}'"), "each layer.channel name once"));
            }
            let mut any = AnyChannel::new(text, FlatSamples::F32(data.to_vec()));
            any.quantize_linearly = false; // linear radiance, not perceptual (matters only to lossy codecs)
            list.push(any);
        }
    }
    if list.is_empty() {
        return Err(Error::param("EXR layers", "no channels", "at least one channel"));
    }
    let layer = exr::image::Layer::new(
        Vec2(width, height),
        LayerAttributes::default(),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list),
    );
    let image = Image::from_layer(layer);
    let mut bytes = std::io::Cursor::new(Vec::new());
    catch_unwind(AssertUnwindSafe(|| image.write().to_buffered(&mut bytes)))
        .map_err(|_| Error::format(path, "EXR encoder panicked"))?
        .map_err(|e| exr_error(path, e, "writing EXR failed"))?;
    super::atomic::write_bytes(path, bytes.get_ref())
}

/// Writes RGB layers: each `(name, pixels)` gives channels `R`, `G`, `B` of layer `name`
/// (`""` = the default layer). See [`write_layers`].
pub fn write_rgb_layers(path: &Path, width: usize, height: usize, layers: &[(&str, &[[f32; 3]])]) -> Result<()> {
    let planes: Vec<(&str, [Vec<f32>; 3])> = layers
        .iter()
        .map(|&(name, px)| (name, [0, 1, 2].map(|c| px.iter().map(|p| p[c]).collect::<Vec<f32>>())))
        .collect();
    let layers: Vec<Layer<'_>> = planes
        .iter()
        .map(|(name, [r, g, b])| Layer {
            name,
            channels: vec![("R", r.as_slice()), ("G", g.as_slice()), ("B", b.as_slice())],
        })
        .collect();
    write_layers(path, width, height, &layers)
}

/// Writes one float32 channel `channel` (e.g. `"Y"` for a height field) in the default layer.
pub fn write_scalar(path: &Path, width: usize, height: usize, channel: &str, data: &[f32]) -> Result<()> {
    write_layers(path, width, height, &[Layer { name: "", channels: vec![(channel, data)] }])
}

/// One channel read back by [`read_layers`]: `(layer, channel, samples)`; layer `""` is the
/// default layer.
pub type ExrChannel = (String, String, Vec<f32>);

/// Every channel of an EXR file as `(layer, channel, samples)`, with the image's
/// `(width, height)`: returns `(width, height, channels)`.
///
/// A channel name `a.b.C` is split at its last `.` into layer `a.b` and channel `C`; names
/// without `.` are in the default layer `""`. In a multi-part file each part's name is
/// prepended to the layer (`part` or `part.layer`). Samples (f16, f32 or u32) are returned as
/// f32, row-major with row 0 the top (first) row, channels in file order (alphabetical within a
/// part). All parts must have the same size; deep data and subsampled channels are rejected.
pub fn read_layers(path: &Path) -> Result<(usize, usize, Vec<ExrChannel>)> {
    crate::scene::load::nonempty_len(path)?;
    let image = catch_unwind(AssertUnwindSafe(|| {
        // `non_parallel`: a panic in a decompressor on exr's rayon pool would abort the process
        // instead of reaching this `catch_unwind` (found by fuzzing, docs/robustness.md).
        read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .all_layers()
            .all_attributes()
            .non_parallel()
            .from_file(path)
    }))
    .map_err(|_| Error::format(path, "EXR decoder panicked (corrupt file)"))?
    .map_err(|e| exr_error(path, e, "truncated or corrupt EXR"))?;
    let mut size = None;
    let mut out = Vec::new();
    for part in &image.layer_data {
        let s = (part.size.width(), part.size.height());
        if *size.get_or_insert(s) != s {
            return Err(Error::format(path, format!("EXR parts differ in size: {s:?} vs {:?}", size.unwrap_or(s))));
        }
        let part_name = part.attributes.layer_name.as_ref().map(|t| t.to_string());
        for ch in &part.channel_data.list {
            if ch.sampling != Vec2(1, 1) {
                return Err(Error::format(
                    path,
                    format!("channel '{}' is subsampled; expected one sample per pixel", ch.name),
                ));
            }
            let full = ch.name.to_string();
            let (layer, channel) = match full.rsplit_once('.') {
                Some((l, c)) => (l.to_string(), c.to_string()),
                None => (String::new(), full.clone()),
            };
            let layer = match (&part_name, layer.is_empty()) {
                (Some(p), true) => p.clone(),
                (Some(p), false) => format!("{p}.{layer}"),
                (None, _) => layer,
            };
            out.push((layer, channel, ch.sample_data.values_as_f32().collect()));
        }
    }
    let (w, h) = size.ok_or_else(|| Error::format(path, "EXR file has no layers"))?;
    Ok((w, h, out))
}

/// Maps an `exr` error to [`Error::Io`] (operating-system errors) or [`Error::Format`].
fn exr_error(path: &Path, e: exr::error::Error, what: &str) -> Error {
    match e {
        exr::error::Error::Io(io) if io.kind() != std::io::ErrorKind::UnexpectedEof => Error::io(path, io),
        other => Error::format(path, format!("{what}: {other}")),
    }
}
