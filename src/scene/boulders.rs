//! `[animation] kind = "boulders"` (docs/blockers.md §6, docs/dynamic.md): the scene's
//! `[[sphere]]`s roll over the terrain. Each sphere circles the field's centre through its
//! initial position (alternate spheres in opposite directions), once every `lap_frames`
//! frames, resting on the bilinear surface under its centre (its lowest point touches the
//! height there). The heights stay; the spheres go through `Renderer::set_spheres` (live
//! inputs: no new pipeline, no submit).

use std::f64::consts::PI;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::scene::model::{Scene, SphereBlocker};
use crate::scene::HeightField;

/// The animation's settings.
#[derive(Clone, Debug, PartialEq)]
pub struct BoulderParams {
    /// Frames per lap around the field's centre, `2..=100000`.
    pub lap_frames: u32,
}

impl Default for BoulderParams {
    fn default() -> Self {
        Self { lap_frames: 24 }
    }
}

impl BoulderParams {
    pub fn validate(&self) -> Result<()> {
        if !(2..=100_000).contains(&self.lap_frames) {
            return Err(Error::param("animation.lap_frames", self.lap_frames, "an integer in 2..=100000"));
        }
        Ok(())
    }
}

/// The rolling spheres of one scene.
#[derive(Clone, Debug)]
pub struct Boulders {
    params: BoulderParams,
    field: HeightField,
    texel_size: f64,
    /// Per sphere: its radius on the circle (world units), its angle at frame 0, its
    /// direction (±1), the sphere itself.
    paths: Vec<(f64, f64, f64, SphereBlocker)>,
    centre: [f64; 2],
}

impl Boulders {
    /// The paths of `scene`'s spheres (an error without spheres).
    pub fn new(params: BoulderParams, scene: &Scene) -> Result<Self> {
        params.validate()?;
        if scene.spheres.is_empty() {
            return Err(Error::param(
                "animation.kind",
                "\"boulders\"",
                "a scene with at least one [[sphere]] (the spheres are what rolls)",
            ));
        }
        let s = scene.texel_size;
        let (w, h) = (scene.field.width() as f64, scene.field.height() as f64);
        let centre = [(w - 1.0) * 0.5 * s, (h - 1.0) * 0.5 * s];
        let paths = scene
            .spheres
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let (dx, dy) = (b.center.x - centre[0], b.center.y - centre[1]);
                let dir = if i % 2 == 0 { 1.0 } else { -1.0 };
                (dx.hypot(dy), dy.atan2(dx), dir, b.clone())
            })
            .collect();
        Ok(Self { params, field: scene.field.clone(), texel_size: s, paths, centre })
    }

    /// The spheres at frame `f`.
    pub fn frame(&self, f: u64) -> Vec<SphereBlocker> {
        let t = (f % u64::from(self.params.lap_frames)) as f64 / f64::from(self.params.lap_frames);
        self.paths
            .iter()
            .map(|(radius, angle, dir, b)| {
                let a = angle + dir * 2.0 * PI * t;
                let (x, y) = (self.centre[0] + radius * a.cos(), self.centre[1] + radius * a.sin());
                let ground = self.field.bilinear(x / self.texel_size, y / self.texel_size);
                SphereBlocker { center: DVec3::new(x, y, ground + b.radius), ..b.clone() }
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spheres_circle_the_centre_resting_on_the_ground() {
        let field =
            HeightField::new("ramp", 32, 32, (0..1024).map(|k| (k % 32) as f32 * 0.5).collect(), 16384).unwrap();
        let mut scene = crate::scene::file::parse_scene("", std::path::Path::new("."), "t", &[]).unwrap();
        scene.field = field;
        scene.spheres = vec![
            SphereBlocker { center: DVec3::new(25.5, 15.5, 3.0), radius: 2.0, albedo: [0.5; 3] },
            SphereBlocker { center: DVec3::new(15.5, 5.5, 3.0), radius: 1.0, albedo: [0.5; 3] },
        ];
        let b = Boulders::new(BoulderParams { lap_frames: 8 }, &scene).unwrap();
        let f0 = b.frame(0);
        assert!((f0[0].center.x - 25.5).abs() < 1e-12 && (f0[0].center.y - 15.5).abs() < 1e-12);
        // Resting on the ramp z = x/2 under its centre.
        assert!((f0[0].center.z - (25.5 * 0.5 + 2.0)).abs() < 1e-9);
        // A quarter lap later the first sphere is a quarter turn on (counter-clockwise), the
        // second a quarter turn back; a full lap returns.
        let f2 = b.frame(2);
        assert!((f2[0].center.x - 15.5).abs() < 1e-9 && (f2[0].center.y - 25.5).abs() < 1e-9, "{:?}", f2[0]);
        assert!((f2[1].center.x - 5.5).abs() < 1e-9 && (f2[1].center.y - 15.5).abs() < 1e-9, "{:?}", f2[1]);
        assert_eq!(b.frame(8), f0);
        scene.spheres.clear();
        assert!(Boulders::new(BoulderParams::default(), &scene).is_err());
        assert!(BoulderParams { lap_frames: 1 }.validate().is_err());
    }
}
