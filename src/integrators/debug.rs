//! The course's Part 1-2 views: shading normals and BVH traversal cost, one camera
//! ray per sample.

use super::{PixelSamples, SampleIntegrator, SampleValue};
use crate::accel::{Accel, TraversalStats};
use crate::camera::Camera;
use crate::geometry::Ray;
use crate::lanes::One;
use crate::sampling::{pixel_key, SampleStream, SamplerKind};
use crate::scene::Scene;
use crate::Color;

/// What a debug view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// `0.5·n + 0.5` of the shading normal at the first hit; black on a miss.
    Normals,
    /// Nodes visited plus primitives tested by the camera ray.
    TraversalCost,
}

pub struct DebugView<'a> {
    pub scene: &'a Scene,
    pub accel: &'a dyn Accel,
    pub camera: &'a Camera,
    pub view: View,
    pub seed: u64,
    pub sampler: SamplerKind,
}

impl DebugView<'_> {
    fn value(&self, ray: &Ray) -> SampleValue {
        match self.view {
            View::Normals => match self.accel.intersect(ray) {
                Some(h) => SampleValue {
                    radiance: 0.5 * self.scene.interaction(ray, &h).ns + Color::splat(0.5),
                    met_surface: true,
                },
                None => SampleValue::default(),
            },
            View::TraversalCost => {
                let mut stats = TraversalStats::default();
                let hit = self.accel.intersect_counted(ray, &mut stats);
                SampleValue {
                    radiance: Color::splat((stats.nodes + stats.prims) as f32),
                    met_surface: hit.is_some(),
                }
            }
        }
    }
}

impl SampleIntegrator for DebugView<'_> {
    fn render_blocks(
        &self,
        blocks: &[PixelSamples],
        stop: &(dyn Fn() -> bool + Sync),
        done: &mut dyn FnMut(usize, &[SampleValue]),
    ) {
        let mut values = Vec::new();
        for (i, b) in blocks.iter().enumerate() {
            if stop() {
                return;
            }
            let pixel = b.y as u64 * self.camera.width as u64 + b.x as u64;
            values.clear();
            for k in 0..b.count {
                let stream = SampleStream::<One> {
                    kind: self.sampler,
                    key: pixel_key(self.seed, pixel),
                    index: b.first + k,
                };
                let pixel = (b.x as f32, b.y as f32);
                let (o, d) = self.camera.sample_rays(One, pixel, &stream);
                values.push(self.value(&Ray::new(o.vec3(), d.vec3())));
            }
            done(i, &values);
        }
    }
}
