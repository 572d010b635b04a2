"""Geotags in the JPEG itself, so the same file goes straight into offline photogrammetry.

EXIF (written with piexif: pure Python, no dependencies, and it inserts the EXIF segment
into the JPEG's bytes without decoding or re-encoding the image, so a geotag costs no
quality and no CPU on the onboard computer; Pillow's Exif API would need Pillow on the
drone and a re-encode to write):

- GPS: GPSLatitude/Ref, GPSLongitude/Ref, GPSAltitude/Ref (above mean sea level, as the
  flight controller reports it), GPSTimeStamp and GPSDateStamp (UTC);
- the exposure time: DateTimeOriginal with SubSecTimeOriginal and OffsetTimeOriginal
  "+00:00" (UTC; OpenDroneMap reads DateTimeOriginal as UTC, and SubSecTime for the
  milliseconds, so that is written too);
- the lens: FocalLength, and the sensor's size as FocalPlaneX/YResolution in pixels per
  centimetre (OpenDroneMap's `opendm/photo.py` computes the sensor width from these and
  the image width, then the focal ratio = focal / sensor width). FocalLengthIn35mmFilm is
  left out on purpose: OpenDroneMap prefers it over the two above, and as an integer it
  is the less precise of the two.

XMP, an APP1 segment of its own after the EXIF one, with the camera's orientation in the
Pix4D/Parrot ``Camera:`` namespace: ``Camera:Roll``, ``Camera:Pitch`` and ``Camera:Yaw``,
which `opendm/photo.py` reads (as attributes, ``@Camera:Yaw``, or elements) when the
DJI-only ``drone-dji:`` tags are absent. Its convention for a nadir camera: yaw 0 puts
the top of the image north, pitch 0 is nadir, roll 0 level; it builds the rotation from
them as an aircraft's yaw-pitch-roll with the top of the image pointing forward. Our
camera is fixed to the body looking down, with the top of the image forward, so the
vehicle's own roll, pitch and yaw (PhotoPose's convention) are those angles unchanged.
(The DJI tags would need Make "DJI", for which OpenDroneMap adds 90 to the pitch.)
"""

from __future__ import annotations

import io
import struct
from datetime import UTC, datetime
from fractions import Fraction

import piexif

from protocol.photos import CameraIntrinsics, PhotoPose

MAKE = "Fleet GCS"
SOFTWARE = "fleet-gcs vehicle agent"
XMP_HEADER = b"http://ns.adobe.com/xap/1.0/\x00"
APP1 = 0xE1
SOI = b"\xff\xd8"

Rational = tuple[int, int]


class NotAJpeg(ValueError):
    """The bytes are not a JPEG whose segments can be walked."""


def geotag(jpeg: bytes, pose: PhotoPose, camera: CameraIntrinsics, *, model: str) -> bytes:
    """``jpeg`` with EXIF and XMP saying where, when, how the camera pointed and its lens."""
    if not jpeg.startswith(SOI):
        raise NotAJpeg("not a JPEG: it does not start with the SOI marker")
    exif = piexif.dump(exif_tags(pose, camera, model=model))
    out = io.BytesIO()
    try:
        piexif.insert(exif, jpeg, out)
    except (ValueError, struct.error, IndexError) as error:
        raise NotAJpeg(f"not a JPEG piexif can tag: {error}") from None
    return insert_app1(out.getvalue(), XMP_HEADER + xmp_packet(pose, camera).encode())


def exif_tags(pose: PhotoPose, camera: CameraIntrinsics, *, model: str) -> dict[str, dict]:  # type: ignore[type-arg]
    when = datetime.fromtimestamp(pose.time, UTC)
    stamp = when.strftime("%Y:%m:%d %H:%M:%S").encode()
    millis = f"{when.microsecond // 1000:03d}".encode()
    # pixels per centimetre of the sensor (FocalPlaneResolutionUnit 3)
    x_per_cm = camera.image_width_px / (camera.sensor_width_mm / 10.0)
    y_per_cm = camera.image_height_px / (camera.sensor_height_mm / 10.0)
    seconds = when.second + when.microsecond / 1e6
    return {
        "0th": {
            piexif.ImageIFD.Make: MAKE.encode(),
            piexif.ImageIFD.Model: model.encode(),
            piexif.ImageIFD.Software: SOFTWARE.encode(),
            piexif.ImageIFD.DateTime: stamp,
            piexif.ImageIFD.Orientation: 1,
        },
        "Exif": {
            piexif.ExifIFD.DateTimeOriginal: stamp,
            piexif.ExifIFD.DateTimeDigitized: stamp,
            piexif.ExifIFD.SubSecTime: millis,
            piexif.ExifIFD.SubSecTimeOriginal: millis,
            piexif.ExifIFD.OffsetTimeOriginal: b"+00:00",
            piexif.ExifIFD.FocalLength: _rational(camera.focal_length_mm, 1000),
            piexif.ExifIFD.FocalPlaneXResolution: _rational(x_per_cm, 1000),
            piexif.ExifIFD.FocalPlaneYResolution: _rational(y_per_cm, 1000),
            piexif.ExifIFD.FocalPlaneResolutionUnit: 3,  # centimetres
            piexif.ExifIFD.PixelXDimension: camera.image_width_px,
            piexif.ExifIFD.PixelYDimension: camera.image_height_px,
        },
        "GPS": {
            piexif.GPSIFD.GPSVersionID: (2, 3, 0, 0),
            piexif.GPSIFD.GPSLatitudeRef: b"N" if pose.lat >= 0 else b"S",
            piexif.GPSIFD.GPSLatitude: _dms(abs(pose.lat)),
            piexif.GPSIFD.GPSLongitudeRef: b"E" if pose.lon >= 0 else b"W",
            piexif.GPSIFD.GPSLongitude: _dms(abs(pose.lon)),
            piexif.GPSIFD.GPSAltitudeRef: 0 if pose.alt_msl >= 0 else 1,
            piexif.GPSIFD.GPSAltitude: _rational(abs(pose.alt_msl), 1000),
            piexif.GPSIFD.GPSTimeStamp: (
                (when.hour, 1),
                (when.minute, 1),
                _rational(seconds, 1000),
            ),
            piexif.GPSIFD.GPSDateStamp: when.strftime("%Y:%m:%d").encode(),
            piexif.GPSIFD.GPSMapDatum: b"WGS-84",
        },
    }


def xmp_packet(pose: PhotoPose, camera: CameraIntrinsics) -> str:
    """The XMP packet: the camera's orientation (see the module's note) and its lens."""
    return (
        '<?xpacket begin="\ufeff" id="W5M0MpCehiHzreSzNTczkc9d"?>'
        '<x:xmpmeta xmlns:x="adobe:ns:meta/">'
        '<rdf:RDF xmlns:rdf="http://www.w3.org/1999/02/22-rdf-syntax-ns#">'
        '<rdf:Description rdf:about=""'
        ' xmlns:Camera="http://pix4d.com/camera/1.0/"'
        ' xmlns:exif="http://ns.adobe.com/exif/1.0/"'
        f' Camera:Roll="{pose.roll:.4f}"'
        f' Camera:Pitch="{pose.pitch:.4f}"'
        f' Camera:Yaw="{pose.yaw % 360.0:.4f}"'
        ' Camera:ModelType="perspective"'
        f' Camera:AboveGroundAltitude="{pose.alt_rel:.3f}"'
        f' exif:FocalLength="{camera.focal_length_mm:g}"'
        f' Camera:SensorWidth="{camera.sensor_width_mm:g}"'
        f' Camera:SensorHeight="{camera.sensor_height_mm:g}"'
        "/></rdf:RDF></x:xmpmeta>"
        '<?xpacket end="w"?>'
    )


def insert_app1(jpeg: bytes, payload: bytes) -> bytes:
    """``jpeg`` with one more APP1 segment, after its leading APP0/APP1 segments (XMP
    follows EXIF, as the XMP specification's part 3 asks)."""
    if len(payload) + 2 > 0xFFFF:
        raise ValueError(f"an APP1 segment holds at most 65533 bytes, not {len(payload)}")
    at = len(SOI)
    while at + 4 <= len(jpeg) and jpeg[at] == 0xFF and jpeg[at + 1] in (0xE0, APP1):
        (length,) = struct.unpack(">H", jpeg[at + 2 : at + 4])
        at += 2 + length
    if at > len(jpeg):
        raise NotAJpeg("a JPEG segment runs past the end of the file")
    segment = bytes([0xFF, APP1]) + struct.pack(">H", len(payload) + 2) + payload
    return jpeg[:at] + segment + jpeg[at:]


def _rational(value: float, denominator: int) -> Rational:
    fraction = Fraction(round(value * denominator), denominator)
    return fraction.numerator, fraction.denominator


def _dms(degrees: float) -> tuple[Rational, Rational, Rational]:
    """Degrees as EXIF's degrees, minutes and seconds (seconds to 1e-5: 0.3 mm)."""
    whole = int(degrees)
    minutes_float = (degrees - whole) * 60.0
    minutes = int(minutes_float)
    seconds = (minutes_float - minutes) * 60.0
    return (whole, 1), (minutes, 1), _rational(seconds, 100_000)
