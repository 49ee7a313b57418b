"""The adaptation image (include/wetclutch/wc_adapt_image.h, DESIGN 12): one clutch's learned values.

The payload of the image format of ``util/image.py`` (magic 0x50414357, the bytes "WCAP", layout version 1),
little-endian::

    offset  0  clutch id                  u32
    offset  4  friction_scale[NODES]      f32 each
    offset 24  confidence[NODES]          f32 each
    offset 44  film_factor                f32
    offset 48  kiss_offset_Pa             f32
    offset 52  shifts_learned             u32

``read_adaptation_image`` returns the values or raises an AdaptationImageError whose ``status`` names the
reason with the firmware's names (wc_adapt_image_load): an image status (``MISSING``, ``TRUNCATED``,
``BAD_MAGIC``, ``BAD_VERSION``, ``BAD_LENGTH``, ``BAD_CRC``), ``WRONG_CLUTCH`` or ``BAD_VALUES``.
``write_adaptation_file`` writes a file atomically (util/atomic.py).
"""
from __future__ import annotations

import math
import struct
from dataclasses import dataclass
from pathlib import Path

from ..util.atomic import open_atomic
from ..util.image import ImageError, image_bytes, read_image, write_image

MAGIC = 0x50414357              # WC_ADAPT_IMAGE_MAGIC, "WCAP"
VERSION = 1                     # WC_ADAPT_IMAGE_VERSION
NODES = 5                       # WC_ADAPT_NODES
PAYLOAD_BYTES = 4 * (2 * NODES + 4)   # WC_ADAPT_IMAGE_PAYLOAD_BYTES (56)
IMAGE_BYTES = image_bytes(PAYLOAD_BYTES)   # WC_ADAPT_IMAGE_BYTES (76)

_PAYLOAD = struct.Struct(f"<I{NODES}f{NODES}fffI")
assert _PAYLOAD.size == PAYLOAD_BYTES


class AdaptationImageError(ImageError):
    """An adaptation image that gives the calibration's values in the firmware; ``status`` says why."""


@dataclass(frozen=True)
class AdaptationValues:
    """wc_adapt_values_t. The defaults are the calibration's values (wc_adapt_reset)."""
    friction_scale: tuple[float, ...] = (1.0,) * NODES
    confidence: tuple[float, ...] = (0.0,) * NODES
    film_factor: float = 1.0
    kiss_offset_Pa: float = 0.0
    shifts_learned: int = 0

    def __post_init__(self) -> None:
        if len(self.friction_scale) != NODES or len(self.confidence) != NODES:
            raise ValueError(f"adaptation values: {NODES} friction scales and confidences, "
                             f"got {len(self.friction_scale)} and {len(self.confidence)}")
        if not 0 <= self.shifts_learned <= 0xFFFFFFFF:
            raise ValueError(f"adaptation values: shifts_learned {self.shifts_learned} outside u32")


@dataclass(frozen=True)
class AdaptationBands:
    """The bands of the shift calibration that wc_adapt_values_valid checks (adapt_* fields, float32)."""
    scale_band: float
    film_factor_min: float
    film_factor_max: float
    kiss_band_Pa: float


def values_problem(values: AdaptationValues, bands: AdaptationBands | None = None) -> str | None:
    """Why the values would fail wc_adapt_values_valid (None: they pass): every float finite, confidences in
    [0, 1], and with bands |scale - 1| <= scale_band, film factor in [min, max], |kiss offset| <= kiss band."""
    floats = {**{f"friction_scale[{i}]": s for i, s in enumerate(values.friction_scale)},
              **{f"confidence[{i}]": c for i, c in enumerate(values.confidence)},
              "film_factor": values.film_factor, "kiss_offset_Pa": values.kiss_offset_Pa}
    for name, x in floats.items():
        if not math.isfinite(x):
            return f"{name} {x} not finite"
    for i, c in enumerate(values.confidence):
        if not 0.0 <= c <= 1.0:
            return f"confidence[{i}] {c} outside [0, 1]"
    if bands is None:
        return None
    for i, s in enumerate(values.friction_scale):
        if not abs(s - 1.0) <= bands.scale_band:
            return f"friction_scale[{i}] {s} outside 1 +- {bands.scale_band}"
    if not bands.film_factor_min <= values.film_factor <= bands.film_factor_max:
        return f"film_factor {values.film_factor} outside [{bands.film_factor_min}, {bands.film_factor_max}]"
    if not abs(values.kiss_offset_Pa) <= bands.kiss_band_Pa:
        return f"kiss_offset_Pa {values.kiss_offset_Pa} outside +- {bands.kiss_band_Pa}"
    return None


def encode_adaptation(values: AdaptationValues, clutch_id: int) -> bytes:
    """The image of clutch clutch_id's values (wc_adapt_image_write): floats rounded to float32."""
    try:
        payload = _PAYLOAD.pack(clutch_id, *values.friction_scale, *values.confidence, values.film_factor,
                                values.kiss_offset_Pa, values.shifts_learned)
    except (struct.error, OverflowError) as e:
        raise ValueError(f"adaptation values of clutch {clutch_id} do not fit the image: {e}") from None
    return write_image(MAGIC, VERSION, payload)


def read_adaptation_image(image: bytes | None, clutch_id: int, bands: AdaptationBands | None = None,
                          what: str = "adaptation image") -> AdaptationValues:
    """Clutch clutch_id's values from image, checked as wc_adapt_image_load checks them (the bands when
    given); an AdaptationImageError naming the reason otherwise."""
    try:
        payload = read_image(image, MAGIC, VERSION, PAYLOAD_BYTES, what)
    except ImageError as e:
        raise AdaptationImageError(e.status, str(e)) from None
    fields = _PAYLOAD.unpack(payload)
    if fields[0] != clutch_id:
        raise AdaptationImageError("WRONG_CLUTCH", f"{what}: WRONG_CLUTCH: the image of clutch {fields[0]}, "
                                                   f"expected clutch {clutch_id}")
    values = AdaptationValues(friction_scale=tuple(fields[1:1 + NODES]),
                              confidence=tuple(fields[1 + NODES:1 + 2 * NODES]),
                              film_factor=fields[-3], kiss_offset_Pa=fields[-2], shifts_learned=fields[-1])
    problem = values_problem(values, bands)
    if problem is not None:
        raise AdaptationImageError("BAD_VALUES", f"{what}: BAD_VALUES: {problem}")
    return values


def read_adaptation_file(path: Path | str, clutch_id: int, bands: AdaptationBands | None = None) -> AdaptationValues:
    """read_adaptation_image of a file; a file that does not exist is MISSING (the firmware's empty store)."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        data = b""
    return read_adaptation_image(data, clutch_id, bands, what=str(path))


def write_adaptation_file(path: Path | str, values: AdaptationValues, clutch_id: int) -> None:
    """The image of the values, written atomically: a reader sees the old file or the whole new one."""
    image = encode_adaptation(values, clutch_id)
    with open_atomic(path, "wb") as f:
        f.write(image)
