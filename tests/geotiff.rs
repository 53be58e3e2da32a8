//! GeoTIFF DEMs (`heightfield.file = "x.tif"`, docs/scene-format.md): every sample type, the
//! pixel-scale tag as the texel size, NoData rejected with its position or filled, and clear
//! errors for what cannot be read. Every file is written here with the `tiff` crate's encoder.

use std::fs::File;
use std::path::{Path, PathBuf};

use hfgi::scene::file::load_scene;
use hfgi::scene::load::{load_heightfield, save_raw, LoadOptions, NoData};
use hfgi::scene::HeightField;
use tiff::encoder::{colortype, Compression, DeflateLevel, TiffEncoder, TiffValue};
use tiff::tags::Tag;

const W: u32 = 5;
const H: u32 = 3;

/// Tags a test adds: pixel scale (x, y), geographic model, NoData text.
#[derive(Default, Clone)]
struct Geo {
    scale: Option<[f64; 2]>,
    geographic: bool,
    nodata: Option<&'static str>,
}

fn write_tiff<C>(path: &Path, data: &[C::Inner], geo: &Geo)
where
    C: colortype::ColorType,
    [C::Inner]: TiffValue,
{
    let mut enc = TiffEncoder::new(File::create(path).unwrap()).unwrap();
    let mut img = enc.new_image::<C>(W, H).unwrap();
    tag_geo(img.encoder(), geo);
    img.write_data(data).unwrap();
}

fn tag_geo<W: std::io::Write + std::io::Seek, K: tiff::encoder::TiffKind>(
    dir: &mut tiff::encoder::DirectoryEncoder<'_, W, K>,
    geo: &Geo,
) {
    if let Some([x, y]) = geo.scale {
        dir.write_tag(Tag::ModelPixelScaleTag, &[x, y, 0.0][..]).unwrap();
    }
    // GeoKeyDirectory: version 1.1.0, 1 key: GTModelTypeGeoKey (1024) = 2 geographic / 1 projected.
    let model = if geo.geographic { 2u16 } else { 1 };
    dir.write_tag(Tag::GeoKeyDirectoryTag, &[1u16, 1, 0, 1, 1024, 0, 1, model][..]).unwrap();
    if let Some(nd) = geo.nodata {
        dir.write_tag(Tag::GdalNodata, nd).unwrap();
    }
}

fn ramp() -> Vec<f64> {
    (0..W * H).map(|i| f64::from(i) * 3.0 - 20.0).collect()
}

fn load(path: &Path) -> Vec<f32> {
    load_heightfield(path, &LoadOptions::default()).unwrap().data().to_vec()
}

fn load_err(path: &Path, opts: &LoadOptions) -> String {
    match load_heightfield(path, opts) {
        Ok(f) => panic!("{} loaded as {}×{}; expected an error", path.display(), f.width(), f.height()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn every_sample_type_is_read_as_stored() {
    let dir = tempfile::tempdir().unwrap();
    let want: Vec<f32> = ramp().iter().map(|&v| v as f32).collect();
    let p = |n: &str| -> PathBuf { dir.path().join(n) };
    let geo = Geo::default();
    write_tiff::<colortype::Gray32Float>(&p("f32.tif"), &ramp().iter().map(|&v| v as f32).collect::<Vec<_>>(), &geo);
    write_tiff::<colortype::Gray64Float>(&p("f64.tiff"), &ramp(), &geo);
    write_tiff::<colortype::GrayI16>(&p("i16.tif"), &ramp().iter().map(|&v| v as i16).collect::<Vec<_>>(), &geo);
    write_tiff::<colortype::GrayI32>(&p("i32.TIF"), &ramp().iter().map(|&v| v as i32).collect::<Vec<_>>(), &geo);
    for name in ["f32.tif", "f64.tiff", "i16.tif", "i32.TIF"] {
        assert_eq!(load(&p(name)), want, "{name}");
    }
    // Unsigned: the ramp shifted up (u16 holds 0..65535; integers are not normalised, unlike PNG).
    let up: Vec<f64> = ramp().iter().map(|v| v + 20.0).collect();
    write_tiff::<colortype::Gray16>(&p("u16.tif"), &up.iter().map(|&v| v as u16).collect::<Vec<_>>(), &geo);
    write_tiff::<colortype::Gray8>(&p("u8.tif"), &up.iter().map(|&v| v as u8).collect::<Vec<_>>(), &geo);
    let want_up: Vec<f32> = up.iter().map(|&v| v as f32).collect();
    assert_eq!(load(&p("u16.tif")), want_up);
    assert_eq!(load(&p("u8.tif")), want_up);
    // Extremes of i16 and u16 survive exactly; height_scale multiplies them.
    let ext: Vec<i16> = (0..W * H).map(|i| if i % 2 == 0 { i16::MIN } else { i16::MAX }).collect();
    write_tiff::<colortype::GrayI16>(&p("ext.tif"), &ext, &geo);
    let f = load_heightfield(&p("ext.tif"), &LoadOptions { height_scale: 0.5, ..LoadOptions::default() }).unwrap();
    assert_eq!(f.data()[0], -16384.0);
    assert_eq!(f.data()[1], 16383.5);
    assert_eq!((f.width(), f.height()), (W as usize, H as usize));
}

#[test]
fn compressed_and_row_order() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<f32> = ramp().iter().map(|&v| v as f32).collect();
    let methods = [
        ("lzw.tif", Compression::Lzw),
        ("deflate.tif", Compression::Deflate(DeflateLevel::Balanced)),
        ("packbits.tif", Compression::Packbits),
    ];
    for (name, method) in methods {
        let path = dir.path().join(name);
        let mut enc = TiffEncoder::new(File::create(&path).unwrap()).unwrap().with_compression(method);
        enc.write_image::<colortype::Gray32Float>(W, H, &data).unwrap();
        let f = load_heightfield(&path, &LoadOptions::default()).unwrap();
        // Row 0 of the image is j = 0 (CONVENTIONS.md), x along a row.
        assert_eq!(f.get(1, 0), data[1], "{name}");
        assert_eq!(f.get(0, 2), data[(2 * W) as usize], "{name}");
    }
}

/// A scene reading `file` with extra `[heightfield]` lines.
fn scene_texel(dir: &Path, file: &str, extra: &str) -> Result<f64, String> {
    let path = dir.join(format!("scene-{}.toml", extra.len()));
    std::fs::write(&path, format!("[heightfield]\nfile = \"{file}\"\n{extra}\n")).unwrap();
    load_scene(&path, &[]).map(|s| s.texel_size).map_err(|e| format!("{e:#}"))
}

#[test]
fn pixel_scale_is_the_texel_size_unless_the_scene_sets_one() {
    let dir = tempfile::tempdir().unwrap();
    let data: Vec<f32> = vec![1.0; (W * H) as usize];
    let d = dir.path();
    write_tiff::<colortype::Gray32Float>(
        &d.join("m30.tif"),
        &data,
        &Geo { scale: Some([30.0, 30.0]), ..Geo::default() },
    );
    assert_eq!(scene_texel(d, "m30.tif", ""), Ok(30.0));
    assert_eq!(scene_texel(d, "m30.tif", "texel_size = 2.5"), Ok(2.5));
    // No tag: the default texel size, 1.
    write_tiff::<colortype::Gray32Float>(&d.join("none.tif"), &data, &Geo::default());
    assert_eq!(scene_texel(d, "none.tif", ""), Ok(1.0));
    // Degrees (geographic) and non-square pixels need an explicit texel size.
    let deg = Geo { scale: Some([0.000833, 0.000833]), geographic: true, ..Geo::default() };
    write_tiff::<colortype::Gray32Float>(&d.join("deg.tif"), &data, &deg);
    let e = scene_texel(d, "deg.tif", "").unwrap_err();
    assert!(e.contains("degrees") && e.contains("heightfield.texel_size"), "{e}");
    assert_eq!(scene_texel(d, "deg.tif", "texel_size = 90.0"), Ok(90.0));
    write_tiff::<colortype::Gray32Float>(
        &d.join("rect.tif"),
        &data,
        &Geo { scale: Some([30.0, 20.0]), ..Geo::default() },
    );
    let e = scene_texel(d, "rect.tif", "").unwrap_err();
    assert!(e.contains("not square") && e.contains("30 × 20"), "{e}");
    // A broken scale tag is an error naming it.
    write_tiff::<colortype::Gray32Float>(
        &d.join("neg.tif"),
        &data,
        &Geo { scale: Some([-1.0, 1.0]), ..Geo::default() },
    );
    let e = scene_texel(d, "neg.tif", "").unwrap_err();
    assert!(e.contains("ModelPixelScaleTag"), "{e}");
}

#[test]
fn nodata_is_rejected_with_its_position_or_filled() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut data: Vec<i16> = ramp().iter().map(|&v| v as i16).collect();
    data[7] = -32768; // texel (2, 1)
    data[9] = -32768;
    let path = d.join("holes.tif");
    write_tiff::<colortype::GrayI16>(&path, &data, &Geo { nodata: Some("-32768"), ..Geo::default() });
    let e = load_err(&path, &LoadOptions::default());
    assert!(e.contains("NoData value -32768 at (x=2, y=1)") && e.contains("2 of 15"), "{e}");
    assert!(e.contains("holes.tif") && e.contains("heightfield.nodata"), "{e}");
    let lowest = *data.iter().filter(|&&v| v != -32768).min().unwrap() as f32;
    let f = load_heightfield(&path, &LoadOptions { nodata: NoData::Lowest, ..LoadOptions::default() }).unwrap();
    assert_eq!((f.data()[7], f.data()[9], f.data()[0]), (lowest, lowest, -20.0));
    let f = load_heightfield(&path, &LoadOptions { nodata: NoData::Value(4.0), ..LoadOptions::default() }).unwrap();
    assert_eq!((f.data()[7], f.data()[9]), (4.0, 4.0));
    // The scene key.
    std::fs::write(d.join("s.toml"), "[heightfield]\nfile = \"holes.tif\"\nnodata = \"lowest\"\n").unwrap();
    assert_eq!(load_scene(&d.join("s.toml"), &[]).unwrap().field.data()[7], lowest);
    std::fs::write(d.join("s.toml"), "[heightfield]\nfile = \"holes.tif\"\nnodata = -1.5\n").unwrap();
    assert_eq!(load_scene(&d.join("s.toml"), &[]).unwrap().field.data()[9], -1.5);
    std::fs::write(d.join("s.toml"), "[heightfield]\nfile = \"holes.tif\"\nnodata = \"zero\"\n").unwrap();
    let e = format!("{:#}", load_scene(&d.join("s.toml"), &[]).unwrap_err());
    assert!(e.contains("heightfield.nodata") && e.contains("lowest"), "{e}");
    // Only for GeoTIFFs: with another format or a generator it is an error, not ignored.
    save_raw(&HeightField::new("t", 2, 2, vec![0.0; 4], 64).unwrap(), &d.join("h.f32")).unwrap();
    for source in ["file = \"h.f32\"\nraw_size = 2", "generator = \"fbm\"\nsize = 8"] {
        std::fs::write(d.join("s.toml"), format!("[heightfield]\n{source}\nnodata = \"lowest\"\n")).unwrap();
        let e = format!("{:#}", load_scene(&d.join("s.toml"), &[]).unwrap_err());
        assert!(e.contains("heightfield.nodata applies to GeoTIFF files"), "{e}");
    }

    // NaN as NoData in a float DEM, and the f32 form of GDAL's usual -3.4028234663852886e+38.
    let mut f32s: Vec<f32> = ramp().iter().map(|&v| v as f32).collect();
    f32s[3] = f32::NAN;
    write_tiff::<colortype::Gray32Float>(&d.join("nan.tif"), &f32s, &Geo { nodata: Some("nan"), ..Geo::default() });
    let e = load_err(&d.join("nan.tif"), &LoadOptions::default());
    assert!(e.contains("NoData value NaN at (x=3, y=0)"), "{e}");
    f32s[3] = -f32::MAX;
    write_tiff::<colortype::Gray32Float>(
        &d.join("min.tif"),
        &f32s,
        &Geo { nodata: Some("-3.4028234663852886e+38"), ..Geo::default() },
    );
    let f = load_heightfield(&d.join("min.tif"), &LoadOptions { nodata: NoData::Lowest, ..LoadOptions::default() });
    assert_eq!(f.unwrap().data()[3], -20.0);
    // All missing: nothing to fill from.
    write_tiff::<colortype::GrayI16>(&d.join("all.tif"), &[7i16; 15], &Geo { nodata: Some("7"), ..Geo::default() });
    let e = load_err(&d.join("all.tif"), &LoadOptions { nodata: NoData::Lowest, ..LoadOptions::default() });
    assert!(e.contains("every sample is NoData"), "{e}");
    // A NaN sample without a NoData tag is the usual non-finite error.
    f32s[3] = f32::NAN;
    write_tiff::<colortype::Gray32Float>(&d.join("nan2.tif"), &f32s, &Geo::default());
    let e = load_err(&d.join("nan2.tif"), &LoadOptions::default());
    assert!(e.contains("NaN at (x=3, y=0)") && !e.contains("NoData"), "{e}");
}

#[test]
fn what_cannot_be_read_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let o = LoadOptions::default();
    // Three bands.
    write_tiff::<colortype::RGB8>(&d.join("rgb.tif"), &[9u8; 45], &Geo::default());
    let e = load_err(&d.join("rgb.tif"), &o);
    assert!(e.contains("rgb.tif") && e.contains("expected one band"), "{e}");
    // Not a TIFF, empty, truncated.
    std::fs::write(d.join("text.tif"), "not a tiff at all").unwrap();
    assert!(load_err(&d.join("text.tif"), &o).contains("not a valid TIFF"));
    std::fs::write(d.join("empty.tif"), "").unwrap();
    assert!(load_err(&d.join("empty.tif"), &o).contains("empty file"));
    let good = d.join("good.tif");
    write_tiff::<colortype::Gray32Float>(&good, &[1.0f32; 15], &Geo::default());
    let bytes = std::fs::read(&good).unwrap();
    for cut in [8, 20, bytes.len() / 2, bytes.len() - 4] {
        std::fs::write(d.join("cut.tif"), &bytes[..cut]).unwrap();
        let e = load_err(&d.join("cut.tif"), &o);
        assert!(e.contains("cut.tif"), "cut at {cut}: {e}");
    }
    // Too large for the device: rejected from the header, before the pixels are read.
    let big = d.join("big.tif");
    let mut enc = TiffEncoder::new(File::create(&big).unwrap()).unwrap();
    enc.write_image::<colortype::Gray8>(40, 2, &[0u8; 80]).unwrap();
    let e = load_err(&big, &LoadOptions { max_dim: 32, ..LoadOptions::default() });
    assert!(e.contains("40×2") && e.contains("32×32"), "{e}");
    // A sample beyond f32's range.
    let mut f64s = ramp();
    f64s[4] = 1e300;
    write_tiff::<colortype::Gray64Float>(&d.join("huge.tif"), &f64s, &Geo::default());
    let e = load_err(&d.join("huge.tif"), &o);
    assert!(e.contains("1e300 at (x=4, y=0)") && e.contains("f32"), "{e}");
}
