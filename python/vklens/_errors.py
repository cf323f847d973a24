"""The exceptions vklens raises, one per kind of failure, so that a caller can act on it."""


class Error(Exception):
    """Base class of every vklens error. ``argument`` is the keyword the error is about
    (``"method"``, ``"source_camera"``, ``"size"``, ``"camera_name"`` …) where it is about
    one, else ``None``."""

    argument = None


class InputError(Error, ValueError):
    """Bad input: an argument, file, key or value that cannot be meant. The message names it."""


class GpuError(Error, RuntimeError):
    """The device failed: a Vulkan call, the driver, or the validation layer."""


class UnsupportedError(GpuError):
    """The device lacks a feature or a limit the work needs (e.g. an image larger than it holds)."""


class IoError(Error, OSError):
    """Reading or writing a file failed; the message names the path."""


class InternalError(Error):
    """A bug in vklens: please report it with the message."""
