//! [`Gpu`]: the adapter, device and queue the crowd runs on.

use crate::error::GpuError;

/// The environment variable that points the Vulkan loader at a driver's ICD file (older loaders).
pub const ICD_ENV: &str = "VK_ICD_FILENAMES";

/// Storage buffers the crowd's compute passes bind (`crowd.wgsl`'s bindings 2 to 9).
const STORAGE_BUFFERS: u32 = 8;
/// Uniform buffers they bind (bindings 0 and 1).
const UNIFORM_BUFFERS: u32 = 2;

/// An open GPU: adapter, device and queue. One per process is enough; crowds borrow it.
#[derive(Debug)]
pub struct Gpu {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    pub(crate) info: wgpu::AdapterInfo,
    pub(crate) limits: wgpu::Limits,
}

impl Gpu {
    /// Opens the first adapter of the compiled-in backends (Vulkan by default; Metal and DirectX 12
    /// with this crate's features `metal` and `dx12`), high-performance first. `WGPU_BACKEND`
    /// (`vulkan`, `metal`, `dx12`) restricts the backends and `WGPU_POWER_PREF` (`low`, `high`) the
    /// preference, as wgpu reads them.
    ///
    /// Errors: [`GpuError::NoAdapter`] naming the backends tried and what to install when none is
    /// found (no Vulkan driver: install the driver's Vulkan ICD and the loader `libvulkan1`, or
    /// point `VK_ICD_FILENAMES` at the ICD json); [`GpuError::Device`] when the adapter refuses a
    /// device with its own limits.
    pub fn new() -> Result<Gpu, GpuError> {
        let desc = wgpu::InstanceDescriptor::from_env_or_default();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(&desc);
        let power =
            wgpu::PowerPreference::from_env().unwrap_or(wgpu::PowerPreference::HighPerformance);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: power,
            force_fallback_adapter: false,
            compatible_surface: None,
        }))
        .map_err(|e| GpuError::NoAdapter {
            what: no_adapter_hint(backends, &e.to_string()),
        })?;
        let info = adapter.get_info();
        let limits = adapter.limits();
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("gpu-crowd"),
            required_features: wgpu::Features::empty(),
            required_limits: limits.clone(),
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        }))
        .map_err(|e| GpuError::Device {
            adapter: describe(&info),
            reason: e.to_string(),
        })?;
        Ok(Gpu {
            device,
            queue,
            info,
            limits,
        })
    }

    /// The crowd on a device the caller already has (an engine's, to draw the crowd from its
    /// buffers in the engine's own passes: [`crate::GpuCrowd::draw_pages`]): `info` names the
    /// adapter (`wgpu::Adapter::get_info`), `device` and `queue` are the engine's (wgpu's handles
    /// are shared, not copied). The crowd's limits are the device's (`wgpu::Device::limits`):
    /// pages are sized to its largest storage binding.
    ///
    /// Errors: [`GpuError::Limit`] when the device offers fewer than the
    /// 8 storage buffers a compute shader stage the crowd's passes bind (`wgpu::Limits::default`
    /// offers 8) or fewer than its 2 uniform buffers.
    pub fn from_wgpu(
        info: wgpu::AdapterInfo,
        device: wgpu::Device,
        queue: wgpu::Queue,
    ) -> Result<Gpu, GpuError> {
        let limits = device.limits();
        let needs = [
            (
                "storage buffers per shader stage",
                STORAGE_BUFFERS,
                limits.max_storage_buffers_per_shader_stage,
            ),
            (
                "uniform buffers per shader stage",
                UNIFORM_BUFFERS,
                limits.max_uniform_buffers_per_shader_stage,
            ),
        ];
        for (what, needed, limit) in needs {
            if limit < needed {
                return Err(GpuError::Limit {
                    what,
                    needed: u64::from(needed),
                    limit: u64::from(limit),
                    adapter: describe(&info),
                });
            }
        }
        Ok(Gpu {
            device,
            queue,
            info,
            limits,
        })
    }

    /// The device the crowds on this GPU run on (for an engine's passes that read their buffers).
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The queue the crowds on this GPU submit to.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }

    /// The adapter's name, device type and backend, e.g.
    /// `llvmpipe (LLVM 15.0.6, 256 bits) (Cpu, Vulkan)`.
    pub fn adapter_name(&self) -> String {
        describe(&self.info)
    }

    /// For tests: [`Gpu::new`], or `None` after printing `skipped: no GPU adapter (...)` when there
    /// is none, so that a test can return early. Panics when there is none and
    /// [`crate::REQUIRE_GPU_ENV`] is `1` (CI, where lavapipe is installed), and when an adapter
    /// exists but refuses a device.
    pub fn open_or_skip() -> Option<Gpu> {
        match Gpu::new() {
            Ok(gpu) => {
                eprintln!("adapter: {}", gpu.adapter_name());
                Some(gpu)
            }
            Err(e @ GpuError::NoAdapter { .. }) => {
                if std::env::var(crate::REQUIRE_GPU_ENV).is_ok_and(|v| v == "1") {
                    panic!("{}=1 but {e}", crate::REQUIRE_GPU_ENV);
                }
                println!("skipped: no GPU adapter ({e})");
                None
            }
            Err(e) => panic!("{e}"),
        }
    }

    /// Whether the adapter is a software rasterizer running on the CPU (Mesa's lavapipe,
    /// SwiftShader): correct, but its timings say nothing about a GPU.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }
}

fn describe(info: &wgpu::AdapterInfo) -> String {
    format!("{} ({:?}, {:?})", info.name, info.device_type, info.backend)
}

/// The message of [`GpuError::NoAdapter`]: the backends tried and what to install.
fn no_adapter_hint(backends: wgpu::Backends, reason: &str) -> String {
    let built = [
        (cfg!(feature = "vulkan"), wgpu::Backends::VULKAN, "Vulkan"),
        (cfg!(feature = "metal"), wgpu::Backends::METAL, "Metal"),
        (cfg!(feature = "dx12"), wgpu::Backends::DX12, "DirectX 12"),
    ];
    let compiled: Vec<&str> = built
        .iter()
        .filter(|(on, _, _)| *on)
        .map(|(_, _, n)| *n)
        .collect();
    // The backends compiled in that the instance was allowed to try.
    let tried: Vec<&str> = built
        .iter()
        .filter(|(on, b, _)| *on && backends.contains(*b))
        .map(|(_, _, n)| *n)
        .collect();
    let icd = std::env::var(ICD_ENV)
        .ok()
        .or_else(|| std::env::var("VK_DRIVER_FILES").ok());
    let env = match std::env::var("WGPU_BACKEND") {
        Ok(v) => format!("; WGPU_BACKEND={v} restricts the backends to {backends:?}"),
        Err(_) => String::new(),
    };
    let icd_note = match icd {
        Some(path) => format!("; the Vulkan loader was pointed at {path}"),
        None => String::new(),
    };
    let compiled_list = if compiled.is_empty() {
        "none".to_string()
    } else {
        compiled.join(", ")
    };
    if tried.is_empty() {
        // Nothing was tried: no driver is missing, the backends allowed are not compiled in.
        return format!(
            "{reason} (backends compiled in: {compiled_list}{env}). None of the backends \
             compiled in was allowed: unset WGPU_BACKEND, or set it to one of them (vulkan, \
             metal, dx12), or build gpu-crowd with the feature of the backend wanted"
        );
    }
    if !tried.contains(&"Vulkan") {
        return format!(
            "{reason} (backends compiled in: {compiled_list}{env}). No {} adapter was found: \
             install the GPU's driver",
            tried.join(" or ")
        );
    }
    format!(
        "{reason} (backends compiled in: {compiled_list}{env}{icd_note}). No Vulkan driver was \
         found: install the GPU driver's Vulkan ICD and the Vulkan loader (Debian/Ubuntu: \
         libvulkan1; Mesa's software driver: mesa-vulkan-drivers), or point {ICD_ENV} \
         (VK_DRIVER_FILES for newer loaders) at the driver's ICD json (NVIDIA: \
         /usr/share/vulkan/icd.d/nvidia_icd.json)"
    )
}
