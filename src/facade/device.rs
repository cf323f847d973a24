//! A headless device: vklens's own Vulkan instance, device and queue, for programs that have
//! no engine of their own (the command line, scripts, the Python package).

use crate::gpu::Gpu;
use crate::host::{Context, ContextOptions as DeviceOptions};
use crate::Result;

/// A headless Vulkan device. `VKLENS_DEVICE` picks it (`cpu`/`lavapipe`, `gpu`, an index or a
/// part of the name; default: the fastest), `VKLENS_VALIDATION=1` turns the Khronos validation
/// layer on.
///
/// ```no_run
/// let device = vklens::Device::new()?;
/// println!("running on {}", device.name());
/// # Ok::<(), vklens::Error>(())
/// ```
pub struct Device {
    ctx: Context,
}

impl Device {
    /// Opens the device the environment names.
    pub fn new() -> Result<Self> {
        Ok(Device {
            ctx: Context::from_env()?,
        })
    }

    /// The device's name, as the driver reports it.
    pub fn name(&self) -> &str {
        self.ctx.gpu().device_name()
    }

    /// The handles passes are built from.
    pub fn gpu(&self) -> &Gpu {
        self.ctx.gpu()
    }

    /// Fails if the validation layer (when on) has reported anything so far.
    pub fn check_validation(&self) -> Result<()> {
        self.ctx.check_validation()
    }

    /// Opens the device `options` name (see [`DeviceOptions::from_env`] for what the
    /// environment sets).
    pub fn with_options(options: DeviceOptions) -> Result<Self> {
        Ok(Device {
            ctx: Context::new(options)?,
        })
    }

    /// The headless context (submission, timing) behind the device.
    pub fn context(&self) -> &Context {
        &self.ctx
    }

    /// A device over a headless context opened with the `host` layer (as the command line
    /// opens it, with its pipeline cache file).
    pub fn from_context(ctx: Context) -> Self {
        Device { ctx }
    }
}
