//! Every field of every push-constant struct at the std430 offset its `hfgi_` twin in
//! `glsl/inc/hfgi_shared.glsl` has, and the same size: the header is parsed, not copied.
use super::*;
use std::mem::{offset_of, size_of};

/// `(field, std430 offset)` of each member of `struct hfgi_<name>`, and the struct's size.
fn glsl_layout(name: &str) -> (Vec<(String, usize)>, usize) {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/glsl/inc/hfgi_shared.glsl");
    let text = std::fs::read_to_string(path).unwrap();
    let start = text.find(&format!("struct hfgi_{name} {{")).unwrap_or_else(|| panic!("hfgi_{name}"));
    let body = &text[start..][..text[start..].find("};").unwrap()];
    let (mut fields, mut at, mut align_max) = (Vec::new(), 0usize, 4usize);
    for line in body.lines().skip(1) {
        let decl = line.split("//").next().unwrap().trim().trim_end_matches(';');
        let Some((ty, var)) = decl.split_once(' ') else { continue };
        let (var, count) = match var.split_once('[') {
            Some((v, n)) => (v, n.trim_end_matches(']').parse::<usize>().unwrap()),
            None => (var, 1),
        };
        let (size, align) = match ty {
            "uint" | "int" | "float" => (4, 4),
            "vec4" | "uvec4" | "ivec4" => (16, 16),
            "mat4" => (64, 16),
            other => panic!("hfgi_{name}: type {other} not handled"),
        };
        at = at.div_ceil(align) * align;
        fields.push((var.trim().to_string(), at));
        at += size * count;
        align_max = align_max.max(align);
    }
    (fields, at.div_ceil(align_max) * align_max)
}

/// Checks `rust` (`(field, offset)` of the Rust struct, padding left out) and the size.
fn check(name: &str, size: usize, rust: &[(&str, usize)]) {
    let (glsl, glsl_size) = glsl_layout(name);
    assert_eq!(size, glsl_size, "{name}: size");
    for (field, offset) in rust {
        let g = glsl.iter().find(|(n, _)| n == field).unwrap_or_else(|| panic!("hfgi_{name} has no {field}"));
        assert_eq!(g.1, *offset, "{name}.{field}: Rust offset {offset}, GLSL std430 offset {}", g.1);
    }
    let named = glsl.iter().filter(|(n, _)| !n.starts_with("pad")).count();
    assert_eq!(named, rust.len(), "{name}: fields listed here vs in the header");
}

macro_rules! layout {
    ($t:ident { $($f:ident),* $(,)? }) => {
        check(&stringify!($t).replace("Gpu", ""), size_of::<$t>(), &[$((stringify!($f), offset_of!($t, $f))),*])
    };
}

#[test]
fn every_shared_struct_matches_the_glsl_header_field_by_field() {
    layout!(PyramidPush { level, wrap, out_width, out_height, scale, flags });
    layout!(VisibilityPush {
        sample_offset,
        sample_count,
        out_offset,
        wrap,
        work_width,
        work_height,
        level_step,
        level_bias,
        texel_size,
        stack_mode,
        flags,
        scan_extent,
        horizon_first,
        sweep_near
    });
    layout!(SweepPush {
        sample_offset,
        sample_count,
        line_first,
        line_count,
        work_width,
        work_height,
        stack_mode,
        flags,
        texel_size,
        hull_capacity,
        reach
    });
    layout!(ShadePush {
        width,
        height,
        work_width,
        work_height,
        set_count,
        wrap,
        glossy,
        albedo_map,
        texel_size,
        accumulate,
        sphere_count,
        key_overlap,
        u_scale,
        next_mode,
        camera,
        specular,
        albedo,
        camera_lo
    });
    layout!(BlockerPush {
        width,
        height,
        work_width,
        work_height,
        sphere_count,
        quad_count,
        texel_size,
        log_eps,
        ratio,
        env_offset,
        ol_step,
        triple_count,
        camera,
        camera_lo,
        log_phong
    });
    layout!(LocalPush {
        width,
        height,
        light_count,
        azimuths,
        texel_size,
        albedo_map,
        glossy,
        exponent,
        albedo,
        specular,
        camera,
        camera_lo
    });
    layout!(IndirectPush {
        work_width,
        work_height,
        wrap,
        level_step,
        level_bias,
        texel_size,
        stack_mode,
        sample_count,
        radiance_levels,
        radiance_stack,
        flags,
        scan_extent,
        specular,
        sample_offset,
        probes,
        radiance_planes,
        radiance_scale
    });
    layout!(GatherPush { width, height, channel_stride, vector, n2, glossy, src_width, src_height, plane, packed });
    layout!(ViewPush { view_proj, width, height, texel_size, packed, eye, eye_lo });
    layout!(WaterPush { width, height, wrap, drop_count, k, retain, rest_level, scale, drops });
    layout!(TruthPush {
        width,
        height,
        wrap,
        azimuths,
        step,
        texel_size,
        sh_visibility,
        indirect,
        row_offset,
        rows,
        azimuth_first,
        azimuth_count,
        march,
        cap,
        accumulate,
        local_nodes,
        cap_dir,
        cap_radiance,
        local_centre,
        local_lo
    });
    check(
        "Level",
        size_of::<GpuLevel>(),
        &[
            ("width", offset_of!(GpuLevel, width)),
            ("height", offset_of!(GpuLevel, height)),
            ("offset", offset_of!(GpuLevel, offset)),
            ("source", offset_of!(GpuLevel, source)),
            ("bias", offset_of!(GpuLevel, bias)),
        ],
    );
}
