//! [`Preview`]: the crowd's stick figures drawn on the GPU straight from its buffers, the way an
//! engine would draw them (a render pass reading [`GpuCrowd::draw_pages`] through
//! [`DRAW_WGSL`](crate::DRAW_WGSL), no read-back of the walkers), into an image.

use bytemuck::{Pod, Zeroable};
use crowd_sim::Camera;
use crowd_sim::render::{Image, RenderStyle, Rgb};

use crate::crowd::{GpuCrowd, scoped};
use crate::error::GpuError;

const SHADER: &str = include_str!("shaders/preview.wgsl");
const COLOR: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Level colours the shader holds (`View::level_colors`); a style's further colours are cycled
/// over these.
const MAX_COLORS: usize = 16;

/// The preview shader's uniform (`struct View` of `preview.wgsl`).
#[repr(C)]
#[derive(Debug, Clone, Copy, Pod, Zeroable)]
struct ViewUniform {
    view_proj: [[f32; 4]; 4],
    eye: [f32; 4],
    size: [f32; 4],
    counts: [u32; 4],
    root_only: [f32; 4],
    grid: [f32; 4],
    level_colors: [[f32; 4]; MAX_COLORS],
}

fn rgba(c: Rgb) -> [f32; 4] {
    [
        f32::from(c[0]) / 255.0,
        f32::from(c[1]) / 255.0,
        f32::from(c[2]) / 255.0,
        1.0,
    ]
}

/// A renderer of a [`GpuCrowd`] into images, on the crowd's device: the ground grid, then the
/// visible walkers' bones coloured by level (2 pixels wide within
/// [`RenderStyle::thick_within_m`], 1 pixel beyond), root-only walkers as 3 x 3 pixel dots at
/// half their height, with a depth test between walkers: the picture
/// `crowd_sim::render::render_frame` draws of the CPU crowd. The walkers are read where
/// [`GpuCrowd::step`] left them, by a vertex shader that includes [`crate::DRAW_WGSL`]: an
/// example of an engine drawing the crowd without reading it back. Only the finished image is
/// copied to the host.
#[derive(Debug)]
pub struct Preview {
    width: u32,
    height: u32,
    style: RenderStyle,
    bones: u32,
    accuracy_levels: u32,
    walker_pipeline: wgpu::RenderPipeline,
    grid_pipeline: wgpu::RenderPipeline,
    /// The crowd's walker buffers, page by page: the crowd this preview draws.
    pages: Vec<wgpu::Buffer>,
    /// Per page its bind group (its uniform block, walkers, joints and the bones) and walkers.
    binds: Vec<(wgpu::BindGroup, u32)>,
    /// One uniform block a page, `block` bytes apart.
    uniform: wgpu::Buffer,
    block: u64,
    /// The ground grid's lines, and their vertex count (none with a grid step of 0).
    grid: Option<(wgpu::Buffer, u32)>,
    color: wgpu::Texture,
    depth: wgpu::TextureView,
    readback: wgpu::Buffer,
    padded_row: u32,
}

impl Preview {
    /// A renderer of `crowd` into `width x height` images (sides `1..=4096`) in `style`'s colours
    /// (its grid step and thick-line distance; [`RenderStyle::map`] and the GIF settings are the
    /// caller's), drawing `bones`: pairs of positions, `0` the root and `1 + k` joint `k` (the
    /// CPU source's `crowd_sim::ClipSource::bones`); a bone is drawn when both ends are among the
    /// walker's joints this frame. `accuracy_levels` is the model's count (the colour of a
    /// level; root-only walkers take [`RenderStyle::root_only`]).
    ///
    /// Errors: [`GpuError::Config`] for a side outside `1..=4096`, no bone or a bone whose end
    /// is beyond `u32`; [`GpuError::Runtime`] from the device.
    pub fn new(
        crowd: &GpuCrowd,
        bones: &[(usize, usize)],
        accuracy_levels: usize,
        style: &RenderStyle,
        width: u32,
        height: u32,
    ) -> Result<Preview, GpuError> {
        if !(1..=4096).contains(&width) || !(1..=4096).contains(&height) {
            return Err(GpuError::Config(format!(
                "a preview of {width} x {height} pixels: the sides must be in 1..=4096"
            )));
        }
        let pairs: Vec<[u32; 2]> = bones
            .iter()
            .map(|&(a, b)| Some([u32::try_from(a).ok()?, u32::try_from(b).ok()?]))
            .collect::<Option<_>>()
            .ok_or_else(|| GpuError::Config("a bone's end is beyond u32".into()))?;
        if pairs.is_empty() {
            return Err(GpuError::Config("a preview needs at least one bone".into()));
        }
        let device = crowd.device();
        scoped(device, "making the preview renderer", || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("preview"),
                source: wgpu::ShaderSource::Wgsl(Preview::wgsl().into()),
            });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("preview"),
                entries: &[
                    entry(0, wgpu::BufferBindingType::Uniform),
                    entry(1, wgpu::BufferBindingType::Storage { read_only: true }),
                    entry(2, wgpu::BufferBindingType::Storage { read_only: true }),
                    entry(3, wgpu::BufferBindingType::Storage { read_only: true }),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("preview"),
                bind_group_layouts: &[&layout],
                push_constant_ranges: &[],
            });
            let pipeline = |label: &str,
                            entry_point: &str,
                            buffers: &[wgpu::VertexBufferLayout<'_>],
                            topology: wgpu::PrimitiveTopology,
                            depth: bool| {
                device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pipeline_layout),
                    vertex: wgpu::VertexState {
                        module: &module,
                        entry_point: Some(entry_point),
                        compilation_options: Default::default(),
                        buffers,
                    },
                    primitive: wgpu::PrimitiveState {
                        topology,
                        ..Default::default()
                    },
                    depth_stencil: Some(wgpu::DepthStencilState {
                        format: DEPTH,
                        depth_write_enabled: depth,
                        depth_compare: if depth {
                            wgpu::CompareFunction::LessEqual
                        } else {
                            wgpu::CompareFunction::Always
                        },
                        stencil: Default::default(),
                        bias: Default::default(),
                    }),
                    multisample: Default::default(),
                    fragment: Some(wgpu::FragmentState {
                        module: &module,
                        entry_point: Some("fs"),
                        compilation_options: Default::default(),
                        targets: &[Some(COLOR.into())],
                    }),
                    multiview: None,
                    cache: None,
                })
            };
            let walker_pipeline = pipeline(
                "preview walkers",
                "walker_vs",
                &[],
                wgpu::PrimitiveTopology::TriangleList,
                true,
            );
            let grid_pipeline = pipeline(
                "preview grid",
                "grid_vs",
                &[wgpu::VertexBufferLayout {
                    array_stride: 12,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3],
                }],
                wgpu::PrimitiveTopology::LineList,
                false,
            );
            let bone_buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("preview bones"),
                size: 8 * pairs.len() as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            crowd
                .queue()
                .write_buffer(&bone_buffer, 0, bytemuck::cast_slice(&pairs));
            // One uniform block a page (its joint slots differ), at offsets the device allows.
            let align = u64::from(device.limits().min_uniform_buffer_offset_alignment);
            let block = (std::mem::size_of::<ViewUniform>() as u64).div_ceil(align) * align;
            let uniform = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("preview views"),
                size: block * crowd.pages().max(1) as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let binds = crowd
                .draw_pages()
                .enumerate()
                .map(|(k, page)| {
                    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some("preview page"),
                        layout: &layout,
                        entries: &[
                            wgpu::BindGroupEntry {
                                binding: 0,
                                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                                    buffer: &uniform,
                                    offset: block * k as u64,
                                    size: wgpu::BufferSize::new(
                                        std::mem::size_of::<ViewUniform>() as u64
                                    ),
                                }),
                            },
                            wgpu::BindGroupEntry {
                                binding: 1,
                                resource: page.walker_buffer.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry {
                                binding: 2,
                                resource: page.joint_buffer.as_entire_binding(),
                            },
                            wgpu::BindGroupEntry {
                                binding: 3,
                                resource: bone_buffer.as_entire_binding(),
                            },
                        ],
                    });
                    (bind, page.walkers as u32)
                })
                .collect();
            let lines = grid_lines(style, crowd.config().field_size_m);
            let grid = (!lines.is_empty()).then(|| {
                let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("preview grid"),
                    size: 4 * lines.len() as u64,
                    usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                });
                crowd
                    .queue()
                    .write_buffer(&buffer, 0, bytemuck::cast_slice(&lines));
                (buffer, (lines.len() / 3) as u32)
            });
            let extent = wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            };
            let texture = |label: &str, format, usage| {
                device.create_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: extent,
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage,
                    view_formats: &[],
                })
            };
            let color = texture(
                "preview colour",
                COLOR,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            );
            let depth = texture(
                "preview depth",
                DEPTH,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )
            .create_view(&Default::default());
            let padded_row = (4 * width).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT)
                * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
            let readback = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("preview read-back"),
                size: u64::from(padded_row) * u64::from(height),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            Preview {
                width,
                height,
                style: style.clone(),
                bones: pairs.len() as u32,
                accuracy_levels: accuracy_levels.min(u32::MAX as usize) as u32,
                walker_pipeline,
                grid_pipeline,
                pages: crowd
                    .draw_pages()
                    .map(|p| p.walker_buffer.clone())
                    .collect(),
                binds,
                uniform,
                block,
                grid,
                color,
                depth,
                readback,
                padded_row,
            }
        })
    }

    /// The preview's shader as it compiles it (WGSL: [`crate::DRAW_WGSL`], then the vertex and
    /// fragment stages `grid_vs`, `walker_vs` and `fs`), for checking it with
    /// another WGSL compiler (CI compiles it with Chromium's WebGPU).
    pub fn wgsl() -> String {
        format!("{}\n{SHADER}", crate::DRAW_WGSL)
    }

    /// Draws `crowd` as `camera` sees it after its last [`GpuCrowd::step`] and returns the image
    /// (`camera`'s aspect and field of view; the image is this preview's size). The buffers,
    /// bind groups and grid were made once by [`Preview::new`]; a frame writes the camera into the
    /// uniforms, draws, and copies the image back.
    ///
    /// Errors: a camera `crowd_sim` refuses ([`GpuError::Crowd`]); another crowd than the one
    /// this preview was made for ([`GpuError::Config`]: its bind groups hold that crowd's
    /// buffers); [`GpuError::Runtime`] from the device.
    pub fn render(&self, crowd: &GpuCrowd, camera: &Camera) -> Result<Image, GpuError> {
        camera.validate()?;
        if !crowd
            .draw_pages()
            .map(|p| p.walker_buffer)
            .eq(self.pages.iter())
        {
            return Err(GpuError::Config(
                "a preview draws the crowd it was made for; make one for this crowd".into(),
            ));
        }
        let device = crowd.device();
        let queue = crowd.queue();
        let colors = &self.style.level_colors;
        let mut level_colors = [[0.0; 4]; MAX_COLORS];
        for (k, c) in level_colors.iter_mut().enumerate() {
            if !colors.is_empty() {
                *c = rgba(colors[k % colors.len()]);
            }
        }
        // The shader cycles over its 16 colours; a style with more keeps its first 16.
        let color_count = colors.len().min(MAX_COLORS) as f32;
        let mut encoder = device.create_command_encoder(&Default::default());
        for (k, page) in crowd.draw_pages().enumerate() {
            let u = ViewUniform {
                view_proj: camera.view_projection().to_cols_array_2d(),
                eye: camera.position.extend(1.0).to_array(),
                size: [
                    self.width as f32,
                    self.height as f32,
                    self.style.thick_within_m,
                    color_count,
                ],
                counts: [self.accuracy_levels, page.joint_slots as u32, self.bones, 0],
                root_only: rgba(self.style.root_only),
                grid: rgba(self.style.grid),
                level_colors,
            };
            queue.write_buffer(&self.uniform, self.block * k as u64, bytemuck::bytes_of(&u));
        }
        {
            let view = self.color.create_view(&Default::default());
            let bg = self.style.background;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("preview"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: f64::from(bg[0]) / 255.0,
                            g: f64::from(bg[1]) / 255.0,
                            b: f64::from(bg[2]) / 255.0,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
            });
            if let (Some((buffer, vertices)), Some((bind, _))) = (&self.grid, self.binds.first()) {
                pass.set_pipeline(&self.grid_pipeline);
                pass.set_bind_group(0, bind, &[]);
                pass.set_vertex_buffer(0, buffer.slice(..));
                pass.draw(0..*vertices, 0..1);
            }
            pass.set_pipeline(&self.walker_pipeline);
            for (bind, walkers) in &self.binds {
                pass.set_bind_group(0, bind, &[]);
                pass.draw(0..6 * self.bones, 0..*walkers);
            }
        }
        encoder.copy_texture_to_buffer(
            self.color.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.readback,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(self.padded_row),
                    rows_per_image: Some(self.height),
                },
            },
            self.color.size(),
        );
        let index = queue.submit([encoder.finish()]);
        let slice = self.readback.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device
            .poll(wgpu::PollType::Wait {
                submission_index: Some(index),
                timeout: None,
            })
            .map_err(|e| GpuError::Runtime(e.to_string()))?;
        rx.recv()
            .map_err(|e| GpuError::Runtime(e.to_string()))?
            .map_err(|e| GpuError::Runtime(format!("reading the preview back: {e}")))?;
        let mut img = Image::new(self.width, self.height, self.style.background)
            .map_err(|e| GpuError::Config(e.to_string()))?;
        {
            let data = slice.get_mapped_range();
            for (y, row) in data
                .chunks_exact(self.padded_row as usize)
                .take(self.height as usize)
                .enumerate()
            {
                let out = &mut img.rgb[3 * y * self.width as usize..][..3 * self.width as usize];
                for (o, p) in out.chunks_exact_mut(3).zip(row.chunks_exact(4)) {
                    o.copy_from_slice(&p[..3]);
                }
            }
        }
        self.readback.unmap();
        Ok(img)
    }
}

/// The ground grid's lines (x, y, z per end) over a field of side `field_m`, as the CPU renderer
/// draws it (at most 10,001 lines a direction).
fn grid_lines(style: &RenderStyle, field_m: f32) -> Vec<f32> {
    let step = style.grid_step_m;
    let mut out = Vec::new();
    if !(step > 0.0 && step.is_finite()) {
        return out;
    }
    let half = 0.5 * field_m;
    let n = (2.0 * half / step).floor() as i64;
    for k in 0..=n.min(10_000) {
        let v = -half + k as f32 * step;
        out.extend_from_slice(&[v, 0.0, -half, v, 0.0, half]);
        out.extend_from_slice(&[-half, 0.0, v, half, 0.0, v]);
    }
    out
}

fn entry(binding: u32, ty: wgpu::BufferBindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}
