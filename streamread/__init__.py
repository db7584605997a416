"""streamread: read graduated linear scales (syringes, cylinders, burettes) from a camera.

>>> from streamread import read_image, ReaderOptions
>>> reading = read_image(bgr_image, ReaderOptions(apparatus="syringe"))
>>> reading.level, reading.sigma, reading.error
"""

from streamread.errors import ConfigError, DependencyError, InputError, StreamreadError
from streamread.profile import Profile, default_profile, load_profile
from streamread.reader import ReaderOptions, calibrate, read_image, read_with
from streamread.types import Calibration, Indicator, Reading

__all__ = [
    "Calibration", "ConfigError", "DependencyError", "Indicator", "InputError", "Profile", "Reading",
    "ReaderOptions", "StreamreadError", "calibrate", "default_profile", "load_profile", "read_image", "read_with",
]
