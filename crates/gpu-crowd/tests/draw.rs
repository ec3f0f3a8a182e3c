//! Drawing the crowd from its own buffers: an engine's shader that includes `DRAW_WGSL` and binds
//! `GpuCrowd::draw_pages` reads every walker's visibility, root and joints exactly as
//! `read_walkers` gives them; a crowd runs on a device the caller made (`Gpu::from_wgpu`) as on
//! the one `Gpu::new` opens. Without a GPU adapter the tests print `skipped: no GPU adapter
//! (...)`, or fail when `MOTION_LOD_REQUIRE_GPU=1` (CI, lavapipe).

use crowd_sim::render::{Image, RenderStyle, render_frame};
use crowd_sim::{Camera, ClipSource, Crowd, CrowdConfig, Scene};
use gpu_crowd::{DRAW_WGSL, Gpu, GpuCrowd, GpuError, GpuOptions, Preview, WalkerJoints};
use lod_policy::DistancePolicy;
use motion_lod::LodSource;

mod common;
use common::{model, motion_model};

const DT: f32 = 1.0 / 30.0;

/// A crowd of `walkers` on `gpu` in small pages, stepped `frames` frames along the ground
/// camera's path under the distance policy; returns the last frame's visible count.
fn stepped(gpu: &Gpu, walkers: usize, frames: usize) -> (GpuCrowd, u64) {
    let model = model();
    let config = CrowdConfig::with_density(walkers, 0.2);
    let options = GpuOptions {
        page_walkers: Some(walkers.div_ceil(3)),
        ..GpuOptions::default()
    };
    let mut crowd = GpuCrowd::new(gpu, model, config, options).expect("the crowd starts");
    let policy = DistancePolicy::for_model(model.lod());
    let field = crowd.config().field_size_m;
    let scene = Scene::Ground;
    let lens = scene.lens(Camera::default(), field);
    let mut visible = 0;
    for f in 0..frames {
        let camera = scene.path(field).camera_at(f as f32 * DT, &lens);
        visible = crowd.step(&policy, &camera, DT).expect("a frame").visible;
    }
    (crowd, visible)
}

/// An engine's compute shader over the crowd's buffers: per walker `[visible, joints, root,
/// joint 0, joint 1, ...]`, `stride` floats, through `DRAW_WGSL`'s functions only.
const COPY: &str = r#"
struct Params { n: u32, slots: u32, stride: u32, pad: u32 }
@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> walkers: array<CrowdWalker>;
@group(0) @binding(2) var<storage, read> joints: array<f32>;
@group(0) @binding(3) var<storage, read_write> out: array<f32>;

@compute @workgroup_size(64)
fn copy(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= params.n) {
        return;
    }
    let w = walkers[i];
    let o = i * params.stride;
    out[o] = select(0.0, 1.0, crowd_visible(w));
    let count = crowd_joint_count(w);
    out[o + 1u] = f32(count);
    let root = crowd_root(w);
    out[o + 2u] = root.x;
    out[o + 3u] = root.y;
    out[o + 4u] = root.z;
    for (var k = 0u; k < count; k++) {
        let p = crowd_joint(w, k, params.slots);
        out[o + 5u + 3u * k] = joints[p];
        out[o + 6u + 3u * k] = joints[p + params.slots];
        out[o + 7u + 3u * k] = joints[p + 2u * params.slots];
    }
}
"#;

/// What `COPY` reads of every walker, page by page through `draw_pages`.
fn read_through_draw_wgsl(crowd: &GpuCrowd, max_joints: usize) -> Vec<(bool, Vec<[f32; 3]>)> {
    let device = crowd.device();
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("draw contract"),
        source: wgpu::ShaderSource::Wgsl(format!("{DRAW_WGSL}\n{COPY}").into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("draw contract"),
        layout: None,
        module: &module,
        entry_point: Some("copy"),
        compilation_options: Default::default(),
        cache: None,
    });
    let stride = 5 + 3 * max_joints;
    let mut all = Vec::new();
    let mut first = 0;
    for page in crowd.draw_pages() {
        assert_eq!(page.first, first, "pages in walker order");
        first += page.walkers;
        let params = [
            page.walkers as u32,
            page.joint_slots as u32,
            stride as u32,
            0,
        ];
        let params_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        crowd
            .queue()
            .write_buffer(&params_buf, 0, bytemuck::cast_slice(&params));
        let bytes = (4 * stride * page.walkers) as u64;
        let out = device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let staging = device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: None,
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: params_buf.as_entire_binding(),
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
                    resource: out.as_entire_binding(),
                },
            ],
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(page.walkers.div_ceil(64) as u32, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&out, 0, &staging, 0, bytes);
        crowd.queue().submit([encoder.finish()]);
        let slice = staging.slice(..);
        slice.map_async(wgpu::MapMode::Read, |r| r.expect("maps"));
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .expect("the copy finishes");
        let floats: Vec<f32> = bytemuck::cast_slice(&slice.get_mapped_range()).to_vec();
        for w in floats.chunks_exact(stride) {
            let count = w[1] as usize;
            assert!(count <= max_joints, "{count} joints");
            let positions = (0..=count)
                .map(|k| [w[2 + 3 * k], w[3 + 3 * k], w[4 + 3 * k]])
                .collect();
            all.push((w[0] == 1.0, positions));
        }
    }
    assert_eq!(first, crowd.len(), "the pages cover the crowd");
    all
}

fn as_arrays(w: &WalkerJoints) -> Vec<[f32; 3]> {
    w.positions.iter().map(|p| p.to_array()).collect()
}

#[test]
fn an_engine_shader_reads_every_walker_through_draw_wgsl_as_read_walkers_gives_it() {
    let Some(gpu) = Gpu::open_or_skip() else {
        return;
    };
    // 60 frames: past the spread of first builds, walkers near the camera hold joints, some at
    // coarser levels, the rest root only; the ground camera leaves many out of view.
    let (crowd, visible) = stepped(&gpu, 600, 60);
    assert!(crowd.pages() >= 3, "{} pages", crowd.pages());
    let read = crowd.read_walkers().expect("read back");
    let drawn = read_through_draw_wgsl(&crowd, model().lod().joints());
    assert_eq!(drawn.len(), read.len());
    let mut with_joints = 0;
    for (i, (d, r)) in drawn.iter().zip(&read).enumerate() {
        // The same floats, bit for bit: the shader copies what the crowd wrote.
        assert_eq!(d.1, as_arrays(r), "walker {i}");
        with_joints += usize::from(d.1.len() > 1);
    }
    let in_view = drawn.iter().filter(|d| d.0).count() as u64;
    assert_eq!(in_view, visible, "crowd_visible against the frame's count");
    // Not vacuous: walkers with joints, walkers root only, walkers in and out of view.
    assert!(with_joints >= 20, "{with_joints} walkers with joints");
    assert!(with_joints < read.len(), "every walker has joints");
    assert!(
        in_view > 0 && (in_view as usize) < read.len(),
        "{in_view} in view"
    );
    println!(
        "{} walkers in {} pages: {with_joints} with joints, {in_view} in view, read through \
         DRAW_WGSL as read_walkers gives them",
        read.len(),
        crowd.pages()
    );
}

/// The adapter's device opened by the test itself, as an engine opens its own, with `limits`.
fn own_device(limits: wgpu::Limits) -> Option<(wgpu::AdapterInfo, wgpu::Device, wgpu::Queue)> {
    let instance = wgpu::Instance::new(&wgpu::InstanceDescriptor::from_env_or_default());
    let adapter = pollster::block_on(instance.request_adapter(&Default::default())).ok()?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("an engine's device"),
        required_limits: limits,
        ..Default::default()
    }))
    .expect("the adapter gives a device with these limits");
    Some((adapter.get_info(), device, queue))
}

#[test]
fn a_crowd_on_the_callers_device_walks_as_on_its_own() {
    let Some(gpu) = Gpu::open_or_skip() else {
        return;
    };
    // WebGPU's default limits (8 storage buffers a stage), as a cautious engine asks for.
    let (info, device, queue) = own_device(wgpu::Limits::default()).expect("the same adapter");
    let engine = Gpu::from_wgpu(info, device, queue).expect("the crowd takes the device");
    let (theirs, _) = stepped(&engine, 300, 40);
    let (ours, _) = stepped(&gpu, 300, 40);
    let a = theirs.read_walkers().expect("read back");
    let b = ours.read_walkers().expect("read back");
    assert_eq!(a, b, "the same walks on the caller's device");
    assert!(
        a.iter().any(|w| w.positions.len() > 1),
        "walkers with joints"
    );

    // A device with fewer storage buffers than the crowd's passes bind: a clear error.
    let (info, device, queue) =
        own_device(wgpu::Limits::downlevel_webgl2_defaults()).expect("a small device");
    match Gpu::from_wgpu(info, device, queue) {
        Err(e @ GpuError::Limit { .. }) => {
            let msg = e.to_string();
            assert!(msg.contains("storage buffers per shader stage"), "{msg}");
            println!("{msg}");
        }
        other => panic!("expected a limit error, got {other:?}"),
    }
}

/// Pixels of `a` that are not its background, and of those the share with a pixel of `b` of the
/// same colour within one pixel (the two rasterisers place a line's pixels a pixel apart at
/// worst).
fn matched(a: &Image, b: &Image, background: [u8; 3]) -> (usize, f64) {
    let (w, h) = (a.width as i64, a.height as i64);
    let mut ink = 0;
    let mut near = 0;
    for y in 0..h {
        for x in 0..w {
            let c = a.pixel(x as u32, y as u32).expect("inside");
            if c == background {
                continue;
            }
            ink += 1;
            let found = (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    (0..w).contains(&u)
                        && (0..h).contains(&v)
                        && b.pixel(u as u32, v as u32) == Some(c)
                })
            });
            near += usize::from(found);
        }
    }
    (ink, near as f64 / ink.max(1) as f64)
}

#[test]
fn the_preview_draws_the_gpu_crowd_as_the_cpu_renderer_draws_the_cpu_crowd() {
    let Some(gpu) = Gpu::open_or_skip() else {
        return;
    };
    let motion = motion_model();
    let source = LodSource::new(motion);
    let config = CrowdConfig {
        seed: 3,
        ..CrowdConfig::with_density(800, 0.2)
    };
    let mut cpu = Crowd::new(&source, config).expect("the CPU crowd");
    let mut crowd =
        GpuCrowd::new(&gpu, model(), config, GpuOptions::default()).expect("the GPU crowd");
    let policy = DistancePolicy::for_model(model().lod());
    let style = RenderStyle::default();
    let field = crowd.config().field_size_m;
    let levels = model().lod().levels().len();
    let lens = Camera {
        image_width: 480,
        image_height: 270,
        aspect: 480.0 / 270.0,
        ..Camera::default()
    };
    let preview = Preview::new(&crowd, source.bones(), levels, &style, 480, 270).expect("preview");
    let out = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("preview");
    std::fs::create_dir_all(&out).expect("a folder for the pictures");
    for scene in [Scene::Ground, Scene::Overview] {
        let lens = scene.lens(lens, field);
        for f in 0..45 {
            let camera = scene.path(field).camera_at(f as f32 * DT, &lens);
            cpu.step(&source, &policy, &camera, DT)
                .expect("a CPU frame");
            crowd.step(&policy, &camera, DT).expect("a GPU frame");
            if f % 22 != 0 {
                continue;
            }
            let theirs = render_frame(&cpu, &camera, &style).expect("the CPU picture");
            let ours = preview.render(&crowd, &camera).expect("the GPU picture");
            let name = format!("{scene:?}-{f}").to_lowercase();
            crowd_sim::render::write_png_atomic(&out.join(format!("{name}-gpu.png")), &ours)
                .expect("writes");
            crowd_sim::render::write_png_atomic(&out.join(format!("{name}-cpu.png")), &theirs)
                .expect("writes");
            let (ink, gpu_in_cpu) = matched(&ours, &theirs, style.background);
            let (cpu_ink, cpu_in_gpu) = matched(&theirs, &ours, style.background);
            let walker_ink = |img: &Image| {
                img.rgb
                    .chunks_exact(3)
                    .filter(|p| **p != style.background && **p != style.grid)
                    .count()
            };
            println!(
                "{name}: GPU {ink} pixels drawn ({} walker), {:.1}% by the CPU within a pixel; \
                 CPU {cpu_ink} ({}), {:.1}% by the GPU",
                walker_ink(&ours),
                100.0 * gpu_in_cpu,
                walker_ink(&theirs),
                100.0 * cpu_in_gpu
            );
            assert!(walker_ink(&ours) > 500, "{name}: walkers drawn");
            assert!(
                gpu_in_cpu > 0.95 && cpu_in_gpu > 0.95,
                "{name}: pictures differ"
            );
        }
    }
    // A preview is made for one crowd (its bind groups hold that crowd's buffers): another
    // crowd, even on the same model and device, is an error rather than a picture of the first.
    let other = GpuCrowd::new(
        &gpu,
        model(),
        CrowdConfig::with_density(50, 0.2),
        GpuOptions::default(),
    )
    .expect("another crowd");
    match preview.render(&other, &Camera::default()) {
        Err(e @ GpuError::Config(_)) => println!("{e}"),
        other => panic!("expected a config error, got {other:?}"),
    }
}
