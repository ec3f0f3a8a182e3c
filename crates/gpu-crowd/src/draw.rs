//! Drawing the crowd where it lives: the buffers an engine's shaders read the walkers' roots and
//! joint positions from after [`GpuCrowd::step`], with no read-back ([`GpuCrowd::draw_pages`],
//! [`DRAW_WGSL`]), and the device they live on ([`GpuCrowd::device`], [`Gpu::from_wgpu`] to run
//! the crowd on an engine's own device).

use crate::crowd::GpuCrowd;
#[cfg(doc)]
use crate::device::Gpu;

/// WGSL declarations for an engine's shaders that read the crowd's buffers: the walker struct
/// (`CrowdWalker`, as the crowd's shaders lay it out) and the functions `crowd_visible`,
/// `crowd_root`, `crowd_height`, `crowd_joint_count`, `crowd_joint` (the index of a joint's `x`
/// in a page's joint buffer; `y` and `z` follow at `+ slots` and `+ 2 slots`) and `crowd_level`.
/// Prepend it to a shader module's source; the file's head comment shows the loop that reads a
/// walker's joints.
///
/// Joint `k` is the `k`-th position after the root in `crowd_sim::Crowd::joint_positions`'s
/// order, so that a bone `(a, b)` of `crowd_sim::ClipSource::bones` joins position `a` and `b`
/// (0 the root, `1 + k` joint `k`). The layout is this crate version's: shaders that include this
/// text stay in step with it.
///
/// An engine's pass over the crowd, page by page (a vertex shader of its own that includes this
/// text and binds `walkers`, `joints` and its uniforms at bindings 0 to 2):
///
/// ```no_run
/// # fn draw(crowd: &gpu_crowd::GpuCrowd, pipeline: &wgpu::RenderPipeline,
/// #         uniforms: &wgpu::Buffer, pass: &mut wgpu::RenderPass<'_>, vertices_per_walker: u32) {
/// // The module: `format!("{}\n{}", gpu_crowd::DRAW_WGSL, my_shader)`, whose vertex stage reads
/// // `var<storage, read> walkers: array<CrowdWalker>` and `var<storage, read> joints: array<f32>`
/// // and takes the page's joint slots from its uniforms (`DrawPage::joint_slots`).
/// // (The bind groups can be made once: the buffers live as long as the crowd.)
/// for page in crowd.draw_pages() {
///     let bind = crowd.device().create_bind_group(&wgpu::BindGroupDescriptor {
///         label: Some("crowd page"),
///         layout: &pipeline.get_bind_group_layout(0),
///         entries: &[
///             wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() },
///             wgpu::BindGroupEntry { binding: 1, resource: page.walker_buffer.as_entire_binding() },
///             wgpu::BindGroupEntry { binding: 2, resource: page.joint_buffer.as_entire_binding() },
///         ],
///     });
///     pass.set_pipeline(pipeline);
///     pass.set_bind_group(0, &bind, &[]);
///     // One instance a walker: `instance_index` is the walker's index in `walkers`.
///     pass.draw(0..vertices_per_walker, 0..page.walkers as u32);
/// }
/// # }
/// ```
///
/// [`crate::Preview`] is such a pass, whole (its shader is `src/shaders/preview.wgsl`).
pub const DRAW_WGSL: &str = include_str!("shaders/draw.wgsl");

/// One page of the crowd's walkers as an engine's shaders bind them ([`GpuCrowd::draw_pages`]).
///
/// Both buffers are storage buffers of the crowd's device, written by [`GpuCrowd::step`] (or
/// [`GpuCrowd::submit`]) and valid until the next frame: bind them read-only
/// (`var<storage, read>`) in a render or compute pass submitted after the frame, on the same
/// queue (after `submit`, the pass runs once the frame in flight is done, without the host
/// waiting for it).
#[derive(Debug, Clone, Copy)]
pub struct DrawPage<'a> {
    /// Index of the page's first walker in the crowd (`crowd_sim::Crowd`'s walker order).
    pub first: usize,
    /// Walkers in the page: indices `0..walkers` of `walker_buffer` (the buffer may be longer).
    pub walkers: usize,
    /// Joint slots of the page: the `slots` argument of `DRAW_WGSL`'s `crowd_joint`.
    pub joint_slots: usize,
    /// The walkers, `array<CrowdWalker>` of [`DRAW_WGSL`].
    pub walker_buffer: &'a wgpu::Buffer,
    /// The joint positions, `array<f32>`, indexed by `DRAW_WGSL`'s `crowd_joint`.
    pub joint_buffer: &'a wgpu::Buffer,
}

impl GpuCrowd {
    /// The crowd's pages as an engine's shaders read them after [`GpuCrowd::step`]: each page's
    /// walker and joint buffers and its walker range (see [`DRAW_WGSL`]). One draw or dispatch
    /// per page covers the crowd.
    pub fn draw_pages(&self) -> impl ExactSizeIterator<Item = DrawPage<'_>> + '_ {
        let mut first = 0;
        self.pages.iter().map(move |page| {
            let out = DrawPage {
                first,
                walkers: page.n,
                joint_slots: page.slots,
                walker_buffer: &page.walkers,
                joint_buffer: &page.joints,
            };
            first += page.n;
            out
        })
    }

    /// The device the crowd's buffers live on: make the pipelines and bind groups that read
    /// [`GpuCrowd::draw_pages`] with it.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue the crowd submits its frames to: submit passes that read its buffers here, after
    /// [`GpuCrowd::step`] or [`GpuCrowd::submit`].
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_host_mirror_of_the_walker_has_a_field_of_4_bytes_per_shader_field() {
        let body = super::DRAW_WGSL
            .split("struct CrowdWalker {")
            .nth(1)
            .and_then(|rest| rest.split('}').next())
            .expect("struct CrowdWalker in DRAW_WGSL");
        let fields = body
            .split(',')
            .filter(|f| f.contains(':'))
            .inspect(|f| assert!(f.contains("f32") || f.contains("u32"), "{f}"))
            .count();
        assert!(fields > 40, "{fields} fields");
        assert_eq!(std::mem::size_of::<crate::crowd::GpuWalker>(), 4 * fields);
        // The crowd's shaders use it (no second definition to drift from it).
        let crowd = include_str!("shaders/crowd.wgsl");
        assert!(crowd.contains("alias Walker = CrowdWalker;"));
        assert!(!crowd.contains("struct Walker"));
    }
}
