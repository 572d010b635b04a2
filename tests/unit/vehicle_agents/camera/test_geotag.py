"""Geotags read back as a photogrammetry tool reads them: the EXIF position is the pose's."""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET
from datetime import UTC, datetime

import pytest
from PIL import ExifTags, Image

from protocol.photos import CameraIntrinsics, PhotoPose
from vehicle_agents.camera.geotag import NotAJpeg, geotag

CAMERA = CameraIntrinsics(
    sensor_width_mm=13.2,
    sensor_height_mm=8.8,
    image_width_px=96,
    image_height_px=64,
    focal_length_mm=8.8,
)
RDF = "{http://www.w3.org/1999/02/22-rdf-syntax-ns#}Description"
PIX4D = "{http://pix4d.com/camera/1.0/}"


def jpeg(width: int = 96, height: int = 64) -> bytes:
    out = io.BytesIO()
    Image.effect_noise((width, height), 60).convert("RGB").save(out, "JPEG", quality=90)
    return out.getvalue()


def degrees(dms: tuple[float, float, float], ref: str) -> float:
    value = float(dms[0]) + float(dms[1]) / 60 + float(dms[2]) / 3600
    return -value if ref in ("S", "W") else value


@pytest.mark.parametrize(
    ("lat", "lon", "alt_msl"),
    [(-35.3632621, 149.1652374, 612.4), (51.4778, -0.0015, -3.25), (0.000001, 179.99999, 0.0)],
)
def test_the_exif_position_time_and_lens_are_the_poses(
    lat: float, lon: float, alt_msl: float
) -> None:
    pose = PhotoPose(
        lat=lat,
        lon=lon,
        alt_msl=alt_msl,
        alt_rel=28.0,
        roll=1.5,
        pitch=-2.25,
        yaw=271.0,
        time=1_764_288_000.625,
    )
    tagged = geotag(jpeg(), pose, CAMERA, model="SimulatedCamera")
    with Image.open(io.BytesIO(tagged)) as image:
        exif = image.getexif()
        gps = exif.get_ifd(ExifTags.IFD.GPSInfo)
        sub = exif.get_ifd(ExifTags.IFD.Exif)
    tags = ExifTags.GPS
    assert degrees(gps[tags.GPSLatitude], gps[tags.GPSLatitudeRef]) == pytest.approx(lat, abs=1e-8)
    assert degrees(gps[tags.GPSLongitude], gps[tags.GPSLongitudeRef]) == pytest.approx(
        lon, abs=1e-8
    )
    below_sea = gps[tags.GPSAltitudeRef] in (1, b"\x01")  # a BYTE: Pillow gives it as bytes
    altitude = float(gps[tags.GPSAltitude]) * (-1 if below_sea else 1)
    assert altitude == pytest.approx(alt_msl, abs=1e-3)
    hours, minutes, seconds = (float(v) for v in gps[tags.GPSTimeStamp])
    day = datetime.strptime(gps[tags.GPSDateStamp], "%Y:%m:%d").replace(tzinfo=UTC)
    assert day.timestamp() + hours * 3600 + minutes * 60 + seconds == pytest.approx(pose.time)
    assert sub[ExifTags.Base.DateTimeOriginal] == "2025:11:28 00:00:00"
    assert sub[ExifTags.Base.SubsecTimeOriginal] == "625"
    assert float(sub[ExifTags.Base.FocalLength]) == pytest.approx(8.8)
    # OpenDroneMap's sensor width: image width / FocalPlaneXResolution (pixels per cm) * 10
    assert sub[ExifTags.Base.FocalPlaneResolutionUnit] == 3
    sensor_mm = 96 / float(sub[ExifTags.Base.FocalPlaneXResolution]) * 10
    assert sensor_mm == pytest.approx(13.2, rel=1e-4)


def test_the_xmp_orientation_is_what_opendronemap_reads() -> None:
    pose = PhotoPose(
        lat=1.0, lon=2.0, alt_msl=50.0, alt_rel=40.0, roll=-3.0, pitch=4.5, yaw=-90.0, time=1e9
    )
    tagged = geotag(jpeg(), pose, CAMERA, model="m")
    with Image.open(io.BytesIO(tagged)) as image:
        xmp = image.info["xmp"]
    # opendm/photo.py finds the packet by its <x:xmpmeta> element, as here
    start, end = xmp.find(b"<x:xmpmeta"), xmp.find(b"</x:xmpmeta>")
    description = ET.fromstring(xmp[start : end + len(b"</x:xmpmeta>")]).find(f".//{RDF}")
    assert description is not None
    assert float(description.attrib[f"{PIX4D}Roll"]) == pytest.approx(-3.0)
    assert float(description.attrib[f"{PIX4D}Pitch"]) == pytest.approx(4.5)
    assert float(description.attrib[f"{PIX4D}Yaw"]) == pytest.approx(270.0)


def test_geotagging_leaves_the_image_data_untouched() -> None:
    original = jpeg()
    tagged = geotag(
        original,
        PhotoPose(lat=1, lon=2, alt_msl=3, alt_rel=4, roll=0, pitch=0, yaw=0, time=1e9),
        CAMERA,
        model="m",
    )
    with Image.open(io.BytesIO(original)) as a, Image.open(io.BytesIO(tagged)) as b:
        assert a.tobytes() == b.tobytes()  # inserted, not re-encoded
    assert tagged.endswith(original[-1000:])


def test_bytes_that_are_not_a_jpeg_are_refused() -> None:
    pose = PhotoPose(lat=1, lon=2, alt_msl=3, alt_rel=4, roll=0, pitch=0, yaw=0, time=1e9)
    with pytest.raises(NotAJpeg):
        geotag(b"GIF89a....", pose, CAMERA, model="m")
