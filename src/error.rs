//! The one error type of vklens.
//!
//! Every fallible function of the library returns [`Result`]. An [`Error`] says what a caller
//! can act on through its [`ErrorKind`]: fix the input, pick another device, retry or report.
//! The command line maps kinds to exit codes in one place (`cli::exit_code`), the Python
//! package to exception classes, the C API to `vkl_error_kind`.

use std::path::{Path, PathBuf};

use ash::vk;

/// What kind of failure an [`Error`] is: what the caller can do about it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// Bad input: a file, key, flag or value that cannot be meant. Fix the input.
    Input,
    /// The device lacks a feature or a limit the work needs. Pick another device or a smaller
    /// job.
    Unsupported,
    /// A Vulkan call failed, the driver could not be loaded, or the validation layer spoke.
    Vulkan,
    /// Reading or writing a file failed.
    Io,
    /// A bug in vklens: please report it.
    Internal,
}

/// A failure, with enough context to act on: the file, key or value for bad input, the feature
/// for unsupported work, the call and `VkResult` for Vulkan, the path for I/O.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Bad input. The message names the file, key or value and what was expected.
    #[error("{0}")]
    Input(String),
    /// Bad input in one argument of a call. `argument` names it in the library's words (the
    /// field of the options struct, the parameter); each front end says it in its own
    /// (`--method` on the command line, `method=` in Python, `options.method` in C), so
    /// `message` never names a flag.
    #[error("{message} (`{argument}`)")]
    Argument {
        /// The argument, as the library's options and a render request's fields name it:
        /// `method`, `source_camera`, `chromatic`, `channel_cameras`, `size`, `camera_name`,
        /// `camera_index`, `format`, `density`, `path`, `pose`, `fstop`, `rolling_shutter`,
        /// `max_error_px`, `ids`, `flow`, `depth`, ….
        argument: &'static str,
        /// What is wrong with it.
        message: String,
    },
    /// The device lacks a feature or limit (named in the message).
    #[error("{0}")]
    Unsupported(String),
    /// A Vulkan call failed.
    #[error("{call} failed: {result}")]
    Vulkan {
        /// The Vulkan entry point (or what vklens was doing).
        call: &'static str,
        /// What it returned.
        result: vk::Result,
    },
    /// The Vulkan library or a device could not be had at all.
    #[error("{0}")]
    NoVulkan(String),
    /// GPU memory could not be allocated.
    #[error("GPU memory allocation failed: {0}")]
    Allocation(#[from] gpu_allocator::AllocationError),
    /// The Khronos validation layer reported messages (only when it is on).
    #[error("Vulkan validation reported {} message(s):\n{}", .0.len(), .0.join("\n"))]
    Validation(Vec<String>),
    /// Reading or writing `path` failed.
    #[error("{}: {message}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What was being done and what the system said.
        message: String,
        /// The system's own classification.
        source_kind: std::io::ErrorKind,
    },
    /// A bug in vklens.
    #[error("internal error (please report): {0}")]
    Internal(String),
}

/// Result of every fallible vklens function.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// What kind of failure this is.
    pub fn kind(&self) -> ErrorKind {
        match self {
            Error::Input(_) | Error::Argument { .. } => ErrorKind::Input,
            Error::Unsupported(_) => ErrorKind::Unsupported,
            Error::Vulkan { .. }
            | Error::NoVulkan(_)
            | Error::Allocation(_)
            | Error::Validation(_) => ErrorKind::Vulkan,
            Error::Io { .. } => ErrorKind::Io,
            Error::Internal(_) => ErrorKind::Internal,
        }
    }

    /// Bad input, described by `message` (which names the file, key or value).
    pub fn input(message: impl Into<String>) -> Self {
        Error::Input(message.into())
    }

    /// Bad input in the argument `argument` (see [`Error::Argument`]).
    pub fn argument(argument: &'static str, message: impl Into<String>) -> Self {
        Error::Argument {
            argument,
            message: message.into(),
        }
    }

    /// The argument an [`Error::Argument`] is about, in the library's words.
    pub fn argument_name(&self) -> Option<&'static str> {
        match self {
            Error::Argument { argument, .. } => Some(argument),
            _ => None,
        }
    }

    /// The message without the argument's name, for a front end that says it in its own
    /// words; the whole message for every other error.
    pub fn message_only(&self) -> String {
        match self {
            Error::Argument { message, .. } => message.clone(),
            other => other.to_string(),
        }
    }

    /// Work the device cannot do, described by `message` (which names the feature or limit).
    pub fn unsupported(message: impl Into<String>) -> Self {
        Error::Unsupported(message.into())
    }

    /// A bug in vklens.
    pub fn internal(message: impl Into<String>) -> Self {
        Error::Internal(message.into())
    }

    /// An I/O failure on `path` while `doing` (e.g. "cannot read camera file").
    pub fn io(path: &Path, doing: &str, e: &std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            message: format!("{doing}: {e}"),
            source_kind: e.kind(),
        }
    }

    /// Whether an I/O failure is about the path itself (it does not exist, is not a file or
    /// folder as needed, or may not be opened) rather than a failure of the machine.
    pub fn is_bad_path(&self) -> bool {
        use std::io::ErrorKind as K;
        matches!(
            self,
            Error::Io { source_kind, .. } if matches!(
                source_kind,
                K::NotFound
                    | K::PermissionDenied
                    | K::NotADirectory
                    | K::IsADirectory
                    | K::ReadOnlyFilesystem
                    | K::InvalidFilename
                    | K::InvalidInput
                    | K::FileTooLarge
                    | K::InvalidData
            )
        )
    }

    /// Prefixes the message with `context` (a file or key), keeping the kind.
    pub fn context(self, context: impl std::fmt::Display) -> Self {
        match self {
            Error::Input(m) => Error::Input(format!("{context}: {m}")),
            Error::Argument { argument, message } => Error::Argument {
                argument,
                message: format!("{context}: {message}"),
            },
            Error::Unsupported(m) => Error::Unsupported(format!("{context}: {m}")),
            Error::Internal(m) => Error::Internal(format!("{context}: {m}")),
            Error::NoVulkan(m) => Error::NoVulkan(format!("{context}: {m}")),
            other => other,
        }
    }

    /// The error of a file that another one names (`by`, e.g. `scene.toml: [optics] camera`):
    /// led by `by`, or for an I/O error (whose message leads with its own path) followed by
    /// it; the kind is unchanged.
    pub fn named_by(self, by: impl std::fmt::Display) -> Self {
        match self {
            Error::Io {
                path,
                message,
                source_kind,
            } => Error::Io {
                path,
                message: format!("{message} (named by {by})"),
                source_kind,
            },
            other => other.context(by),
        }
    }
}

impl From<crate::model::ModelError> for Error {
    fn from(e: crate::model::ModelError) -> Self {
        Error::Input(e.to_string())
    }
}

/// Names the Vulkan call of a failed `VkResult`.
pub(crate) trait VkCall<T> {
    /// Maps a `vk::Result` error to [`Error::Vulkan`] naming `call`.
    fn call(self, call: &'static str) -> Result<T>;
}

impl<T> VkCall<T> for std::result::Result<T, vk::Result> {
    fn call(self, call: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vulkan { call, result })
    }
}

thread_local! {
    /// Whether a panic on this thread is expected and caught (see [`catch_quietly`]).
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f`, returning a panic inside it as `Err` without printing it: for third-party code
/// that panics on malformed input (the error is reported as the input's instead). Panics
/// anywhere else still reach the process's panic hook as before.
pub(crate) fn catch_quietly<T>(
    f: impl FnOnce() -> T + std::panic::UnwindSafe,
) -> std::thread::Result<T> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info)
            }
        }));
    });
    let outer = QUIET.with(|q| q.replace(true));
    let result = std::panic::catch_unwind(f);
    QUIET.with(|q| q.set(outer));
    result
}
