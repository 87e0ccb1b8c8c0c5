//! Opening a Vulkan device with wgpu.

use std::fmt;

/// A wgpu device on the Vulkan backend, with the adapter it came from.
pub struct Gpu {
    pub(crate) adapter: wgpu::Adapter,
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
}

/// No usable adapter: the Vulkan loader found no device (install a driver, or
/// `mesa-vulkan-drivers` for lavapipe, Mesa's CPU implementation), or the adapter it found
/// would not create a device.
#[derive(Clone, Debug)]
pub struct NoAdapter {
    /// What wgpu reported.
    pub reason: String,
}

impl fmt::Display for NoAdapter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "no usable Vulkan adapter ({}); a machine without a GPU needs lavapipe, Mesa's CPU \
             Vulkan driver (Debian/Ubuntu package `mesa-vulkan-drivers`)",
            self.reason
        )
    }
}

impl std::error::Error for NoAdapter {}

/// Which adapter a [`Gpu`] runs on, for logs and test output.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AdapterSummary {
    /// The adapter's name (`llvmpipe (LLVM …)` for lavapipe).
    pub name: String,
    /// Discrete, integrated, virtual, CPU or other.
    pub device_type: wgpu::DeviceType,
    /// The driver's name and version as the driver reports them.
    pub driver: String,
    /// The backend (always Vulkan here).
    pub backend: wgpu::Backend,
}

impl fmt::Display for AdapterSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} ({:?}, {:?}, driver {})", self.name, self.device_type, self.backend, self.driver)
    }
}

impl Gpu {
    /// Opens the best Vulkan adapter: wgpu sorts discrete GPUs first, then integrated, other,
    /// virtual and last CPU adapters, so on a machine without a GPU this is lavapipe
    /// (`llvmpipe`, device type [`wgpu::DeviceType::Cpu`]). The device has no optional features
    /// but timestamp queries and f64 shaders (each when offered) and wgpu's default limits.
    pub fn new() -> Result<Gpu, NoAdapter> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            force_fallback_adapter: false,
            compatible_surface: None,
            ..Default::default()
        }))
        .map_err(|e| NoAdapter { reason: e.to_string() })?;
        // GPU timestamps time the passes themselves (`Rendered::gpu_time`) where the adapter
        // has them (lavapipe does); f64 arithmetic in shaders (`shaderFloat64`, lavapipe has
        // it) lets the f64 evaluation run (`F64Sky`). Nothing else is optional.
        // Passthrough shaders hand the f64 modules to the driver as written: wgpu's own path
        // re-reads SPIR-V with naga and drops the `NoContraction` decorations they depend on
        // (see `gdsky_naga::exact_arithmetic`).
        let required_features = adapter.features()
            & (wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::SHADER_F64 | wgpu::Features::PASSTHROUGH_SHADERS);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("skyrun"),
            required_features,
            required_limits: wgpu::Limits::default(),
            ..Default::default()
        }))
        .map_err(|e| NoAdapter {
            reason: format!("adapter `{}` would not create a device: {e}", adapter.get_info().name),
        })?;
        Ok(Gpu { adapter, device, queue })
    }

    /// Whether renders are timed with GPU timestamp queries (the adapter offers
    /// `TIMESTAMP_QUERY`), so [`crate::Rendered::gpu_time`] is set.
    pub fn has_timestamps(&self) -> bool {
        self.device.features().contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Whether shaders may compute in f64 (the device has `Features::SHADER_F64`), as
    /// [`crate::F64Sky`] needs.
    pub fn has_f64(&self) -> bool {
        self.device.features().contains(wgpu::Features::SHADER_F64)
    }

    /// Whether SPIR-V can be given to the driver as is (`Features::PASSTHROUGH_SHADERS`), as
    /// [`crate::F64Sky`] needs for its exact arithmetic.
    pub fn has_passthrough(&self) -> bool {
        self.device.features().contains(wgpu::Features::PASSTHROUGH_SHADERS)
    }

    /// The adapter this device runs on.
    pub fn adapter_info(&self) -> AdapterSummary {
        let info = self.adapter.get_info();
        let driver = match (info.driver.is_empty(), info.driver_info.is_empty()) {
            (false, false) => format!("{} {}", info.driver, info.driver_info),
            (false, true) => info.driver,
            (true, _) => info.driver_info,
        };
        AdapterSummary { name: info.name, device_type: info.device_type, driver, backend: info.backend }
    }

    /// The wgpu adapter, for callers that need more than [`render`](crate::render).
    pub fn adapter(&self) -> &wgpu::Adapter {
        &self.adapter
    }

    /// The wgpu device.
    pub fn device(&self) -> &wgpu::Device {
        &self.device
    }

    /// The device's queue.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.queue
    }
}
