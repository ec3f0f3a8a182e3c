//! [`HostState`]: what a host other than this crate's needs to run a GPU crowd's frames with the
//! same shaders (a web page on WebGPU, say): the compute shaders' source, each page's buffers as
//! they stand, the passes of a frame and the frame uniform of each step. The crate's own tests run
//! such a host in headless Chromium against the crowd here (`viewer/checks/webgpu.mjs`).

use crowd_sim::Camera;
use lod_policy::LevelPolicy;

use crate::crowd::{C_BUILDS, C_NONFINITE, GpuCrowd, groups};
use crate::error::GpuError;

/// How a binding of the crowd's bind group (`@group(0)` of [`HostState::wgsl`]) is declared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostBinding {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read_write>`.
    Storage,
    /// `var<storage, read>`.
    ReadOnlyStorage,
}

/// One buffer of a page's bind group with its contents.
#[derive(Debug, Clone)]
pub struct HostBuffer {
    /// Its `@binding`.
    pub binding: u32,
    /// How it is declared.
    pub kind: HostBinding,
    /// Its bytes (the frame uniform's, binding 0, are those of the last frame; a host writes
    /// [`GpuCrowd::frame_uniforms`] before each frame).
    pub bytes: Vec<u8>,
}

/// How a pass of a frame is dispatched, with the page's bind group (every binding but 10) unless
/// said otherwise.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HostDispatch {
    /// Over the page's walkers: [`HostPage::workgroups`] (x, y).
    Walkers,
    /// One workgroup.
    One,
    /// One workgroup, with a bind group of the counters (binding 3) and the dispatch arguments
    /// (binding 10) instead of the page's: `build_args`, which writes the arguments.
    Arguments,
    /// Indirect, its arguments read from the dispatch arguments (binding 10) at offset 0 (which
    /// the page's bind group does not hold: WebGPU forbids a dispatch to bind for writing the
    /// buffer it reads its arguments from).
    Indirect,
}

/// One page of walkers with its buffers.
#[derive(Debug, Clone)]
pub struct HostPage {
    /// Its walkers.
    pub walkers: usize,
    /// Workgroups (x, y) of a pass over its walkers.
    pub workgroups: [u32; 2],
    /// The buffers by binding: 0 to 9 the page's bind group, 10 the dispatch arguments.
    pub buffers: Vec<HostBuffer>,
}

/// A crowd's state for another host (see the module documentation).
#[derive(Debug, Clone)]
pub struct HostState {
    /// The compute shaders ([`crate::crowd_wgsl`] of the crowd's model and config).
    pub wgsl: String,
    /// The passes of a frame of 30 or 60 fps, in order, each an entry point of `wgsl` (a frame
    /// long enough to be split into rounds needs the counters between them: see
    /// [`GpuCrowd::step`]).
    pub passes: Vec<(&'static str, HostDispatch)>,
    /// What a frame writes into the counters (binding 3) before its passes: `(byte offset,
    /// values)`.
    pub counter_resets: Vec<(u64, Vec<u32>)>,
    /// The pages.
    pub pages: Vec<HostPage>,
}

impl GpuCrowd {
    /// The crowd as it stands after its last frame, for another host to run the next frames with
    /// the same shaders (reads every buffer back: slow, for tests and hand-overs). A frame
    /// [`GpuCrowd::submit`] left in flight is finished first, its statistics dropped.
    ///
    /// Errors: [`GpuError::Memory`] and [`GpuError::Runtime`] from the device.
    pub fn host_state(&mut self) -> Result<HostState, GpuError> {
        // A frame `submit` left in flight ends first (its statistics are not returned).
        self.finish()?;
        let passes = self
            .round_passes(None)
            .into_iter()
            .flatten()
            .map(|(entry, _, dispatch)| (entry, dispatch))
            .chain([("pose_fk", HostDispatch::Walkers)])
            .collect();
        let read = |b: &wgpu::Buffer| self.read_buffer::<u8>(b);
        let [md, mtab] = &self.model_buffers;
        let (md, mtab) = (read(md)?, read(mtab)?);
        let frame_bytes = std::mem::size_of::<crate::crowd::FrameUniform>();
        let mut pages = Vec::new();
        for page in &self.pages {
            use HostBinding::*;
            let buffers = [
                (0, Uniform, vec![0u8; frame_bytes]),
                (1, Uniform, mtab.clone()),
                (2, Storage, read(&page.walkers)?),
                (3, Storage, read(&page.counters)?),
                (4, Storage, read(&page.lists[0])?),
                (5, Storage, read(&page.lists[1])?),
                (6, ReadOnlyStorage, md.clone()),
                (7, Storage, read(&page.lists[2])?),
                (8, Storage, read(&page.lists[3])?),
                (9, Storage, read(&page.joints)?),
                (10, Storage, read(&page.args)?),
            ];
            let (gx, gy) = groups(page.n);
            pages.push(HostPage {
                walkers: page.n,
                workgroups: [gx, gy],
                buffers: buffers
                    .into_iter()
                    .map(|(binding, kind, bytes)| HostBuffer {
                        binding,
                        kind,
                        bytes,
                    })
                    .collect(),
            });
        }
        Ok(HostState {
            wgsl: self.wgsl.clone(),
            passes,
            counter_resets: vec![
                (4 * C_BUILDS as u64, vec![0; 3]),
                (4 * C_NONFINITE as u64, self.counters_reset.clone()),
            ],
            pages,
        })
    }

    /// The frame uniform (binding 0) of each page for a step of `dt` seen from `camera` under
    /// `policy`, as [`GpuCrowd::step`] would write it; the crowd does not move.
    ///
    /// Errors: those of `step` before it runs anything (a bad `dt`, camera or policy).
    pub fn frame_uniforms<P: LevelPolicy + ?Sized>(
        &mut self,
        policy: &P,
        camera: &Camera,
        dt: f32,
    ) -> Result<Vec<Vec<u8>>, GpuError> {
        let mut uniform = self.frame_uniform(policy, camera, dt)?;
        Ok(self
            .pages
            .iter()
            .map(|page| {
                uniform.n = page.n as u32;
                uniform.n_slots = page.slots as u32;
                bytemuck::bytes_of(&uniform).to_vec()
            })
            .collect())
    }
}
