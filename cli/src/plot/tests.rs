//! Unit tests of the Pareto front, the tick labels and the plots.

use super::scale::format_tick;
use super::*;

#[test]
fn front_basic_and_sorted_by_time() {
    // 0: slow, accurate; 1: fast, inaccurate; 2: dominated by 3; 3: middle.
    let pts = [(10.0, 0.01), (1.0, 1.0), (6.0, 0.5), (5.0, 0.1)];
    assert_eq!(pareto_front(&pts), vec![1, 3, 0]);
}

#[test]
fn front_ties() {
    // Same time: only the lower error survives.
    assert_eq!(pareto_front(&[(1.0, 0.5), (1.0, 0.2)]), vec![1]);
    // Same error: only the faster survives.
    assert_eq!(pareto_front(&[(2.0, 0.2), (1.0, 0.2)]), vec![1]);
    // Same error as a faster point but slower, plus a strictly better slower point.
    assert_eq!(pareto_front(&[(1.0, 0.2), (2.0, 0.2), (3.0, 0.1)]), vec![0, 2]);
}

#[test]
fn front_duplicates_are_all_kept() {
    let pts = [(2.0, 0.1), (1.0, 0.5), (2.0, 0.1), (3.0, 0.3)];
    assert_eq!(pareto_front(&pts), vec![1, 0, 2]);
}

#[test]
fn front_skips_non_finite() {
    let pts =
        [(f64::NAN, 0.0), (1.0, f64::NAN), (2.0, 0.5), (f64::INFINITY, 0.0), (3.0, f64::NEG_INFINITY), (4.0, 0.1)];
    assert_eq!(pareto_front(&pts), vec![2, 5]);
    assert!(pareto_front(&[]).is_empty());
    assert!(pareto_front(&[(f64::NAN, f64::NAN)]).is_empty());
}

#[test]
fn front_matches_brute_force() {
    // Deterministic pseudo-random points on a coarse grid (many ties and duplicates).
    let mut state = 0x2545_f491_u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state % 7) as f64
    };
    for _ in 0..200 {
        let pts: Vec<(f64, f64)> = (0..12).map(|_| (next(), next())).collect();
        let dominated = |i: usize| {
            pts.iter().any(|q| {
                let p = pts[i];
                q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1)
            })
        };
        let mut expected: Vec<usize> = (0..pts.len()).filter(|&i| !dominated(i)).collect();
        expected.sort_by(|&a, &b| pts[a].0.total_cmp(&pts[b].0).then(pts[a].1.total_cmp(&pts[b].1)).then(a.cmp(&b)));
        assert_eq!(pareto_front(&pts), expected, "{pts:?}");
    }
}

#[test]
fn tick_format() {
    assert_eq!(format_tick(1.0), "1");
    assert_eq!(format_tick(20.0), "20");
    assert_eq!(format_tick(0.001), "0.001");
    assert_eq!(format_tick(0.002), "0.002");
    assert_eq!(format_tick(1e-5), "1e-5");
    assert_eq!(format_tick(3e-7), "3e-7");
    assert_eq!(format_tick(1e6), "1e6");
    assert_eq!(format_tick(10000.0), "10000");
}

fn sample_points() -> Vec<Point> {
    let mut pts = Vec::new();
    for (i, n) in [16, 32, 64, 128, 256].iter().enumerate() {
        let t = 0.4 * 2f64.powi(i as i32);
        pts.push(Point {
            label: format!("sh order 4, {n} dirs"),
            time_ms: t,
            error: 0.08 / (1.0 + i as f64).powf(1.5),
            group: "spherical harmonics".into(),
        });
        pts.push(Point {
            label: format!("horizon {n}"),
            time_ms: t * 1.7,
            error: 0.05 / (1.0 + i as f64).powi(2),
            group: "horizon-based".into(),
        });
        pts.push(Point {
            label: format!("ray march {n}"),
            time_ms: t * 6.0,
            error: 0.2 / (1.0 + 2.0 * i as f64).powi(2),
            group: "ray marching".into(),
        });
    }
    pts.push(Point { label: "broken".into(), time_ms: f64::NAN, error: 0.1, group: "ray marching".into() });
    pts.push(Point { label: "exact".into(), time_ms: 3.0, error: 0.0, group: "horizon-based".into() });
    pts
}

fn decode(path: &Path) -> image::DynamicImage {
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));
    image::load_from_memory_with_format(&bytes, image::ImageFormat::Png).unwrap()
}

/// Copies a test image out for inspection when the named variable is set.
fn keep(path: &Path, var: &str) {
    if let Some(out) = std::env::var_os(var) {
        std::fs::copy(path, out).unwrap();
    }
}

#[test]
fn plot_writes_decodable_png() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("pareto.png");
    let note = pareto_plot(
        &path,
        "Indirect light: error vs. time",
        "time per frame (ms)",
        "RMSE",
        &sample_points(),
        Some(250.0),
    )
    .unwrap();
    let img = decode(&path).to_rgb8();
    assert_eq!(img.dimensions(), (WIDTH, HEIGHT));
    // Something beyond the white background and grey grid was drawn.
    assert!(img.pixels().any(|p| p.0 == [0, 0, 0]));
    let note = note.expect("two points are skipped");
    assert!(note.contains("skipped 2 of 17"), "{note}");
    keep(&path, "HFGI_PLOT_TEST_OUT");
}

#[test]
fn plot_without_font_and_degenerate_input() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("no-text.png");
    let mut notes = Vec::new();
    draw(&path, "t", "x", "y", &sample_points(), Some(-1.0), None, &mut notes).unwrap();
    assert_eq!(decode(&path).width(), WIDTH);
    assert!(notes.iter().any(|n| n.contains("reference")), "{notes:?}");
    keep(&path, "HFGI_PLOT_TEST_OUT_NOTEXT");

    // Nothing plottable, a single point and identical points must not fail either.
    for pts in [
        vec![],
        vec![Point { label: "a".into(), time_ms: 2.0, error: 0.5, group: "g".into() }],
        vec![Point { label: String::new(), time_ms: 2.0, error: 0.5, group: String::new() }; 3],
    ] {
        let note = pareto_plot(&path, "", "x", "y", &pts, None).unwrap();
        decode(&path);
        assert_eq!(note.is_some_and(|n| n.contains("no plottable")), pts.is_empty());
    }
}
