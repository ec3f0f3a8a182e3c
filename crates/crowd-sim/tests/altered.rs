//! The procedural source with one part of it changed: what a source may report or do wrong.

use crowd_sim::testing::{ProceduralClip, ProceduralSource};
use crowd_sim::{ClipError, ClipSource, LevelTable};
use glam::Vec3;
use lod_policy::{ControlRange, Controls, Detail, RootMotion};

/// [`ProceduralSource`] with its level table replaced (when `levels` is set), the controls of
/// each clip it builds passed through `controls`, and each pose it writes passed through `pose`.
#[derive(Clone)]
pub struct Altered {
    pub inner: ProceduralSource,
    pub levels: Option<LevelTable>,
    pub controls: fn(&Controls) -> Controls,
    pub pose: fn(&mut [f32]),
}

impl Altered {
    /// The source as it is, to be altered field by field.
    pub fn new(inner: ProceduralSource) -> Altered {
        Altered {
            inner,
            levels: None,
            controls: |c| *c,
            pose: |_| {},
        }
    }

    /// The source reporting `levels` instead of its own table.
    pub fn with_levels(inner: ProceduralSource, levels: LevelTable) -> Altered {
        Altered {
            levels: Some(levels),
            ..Altered::new(inner)
        }
    }
}

impl ClipSource for Altered {
    type Clip = ProceduralClip;
    fn levels(&self) -> LevelTable {
        self.levels.unwrap_or_else(|| self.inner.levels())
    }
    fn control_range(&self) -> ControlRange {
        self.inner.control_range()
    }
    fn new_clip(&self) -> ProceduralClip {
        self.inner.new_clip()
    }
    fn build_clip(
        &self,
        c: &Controls,
        d: Detail,
        clip: &mut ProceduralClip,
    ) -> Result<(), ClipError> {
        self.inner.build_clip(&(self.controls)(c), d, clip)
    }
    fn clip_duration(&self, clip: &ProceduralClip) -> f32 {
        self.inner.clip_duration(clip)
    }
    fn clip_root_motion(&self, clip: &ProceduralClip) -> RootMotion {
        self.inner.clip_root_motion(clip)
    }
    fn pose(&self, clip: &ProceduralClip, t: f32, out: &mut [f32]) -> usize {
        let rows = self.inner.pose(clip, t, out);
        (self.pose)(out);
        rows
    }
    fn joints(&self, clip: &ProceduralClip, pose: &[f32], out: &mut [Vec3]) -> usize {
        self.inner.joints(clip, pose, out)
    }
    fn bones(&self) -> &[(usize, usize)] {
        self.inner.bones()
    }
}
