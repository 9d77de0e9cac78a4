//! The native BVH: a flat node array, binned-SAH or midpoint builders.

use super::{Accel, BvhBuilder};
use crate::geometry::Ray;
use crate::scene::{PrimHit, Scene};

pub struct Bvh {}

impl Bvh {
    pub fn build(_scene: &Scene, _builder: BvhBuilder) -> Bvh {
        todo!("bvh: build")
    }
}

impl Accel for Bvh {
    fn intersect(&self, _ray: &Ray) -> Option<PrimHit> {
        todo!()
    }
    fn occluded(&self, _ray: &Ray) -> bool {
        todo!()
    }
    fn name(&self) -> String {
        "native BVH".into()
    }
    fn memory_bytes(&self) -> usize {
        0
    }
}
