"""The hub's photo ingest on a real (migrated SQLite) store and real files: chunks at
offsets, the checks and their recorded refusals, the survey a photo belongs to, the sink,
and the zip export for OpenDroneMap."""

from __future__ import annotations

import asyncio
import io
import shutil
import time
import zipfile
from collections.abc import Callable
from pathlib import Path

import pytest
from PIL import Image

from backend.errors import NotFound
from backend.imagery.mosaic.service import MosaicService
from backend.imagery.photos.checks import Refusal, Refused
from backend.imagery.photos.export import write_zip
from backend.imagery.photos.ingest import OffsetMismatch, PhotoIngest
from backend.imagery.photos.partials import PartialLimits
from backend.imagery.photos.repository import PhotoRepository
from backend.imagery.photos.stored import PhotoSink, StoredPhoto
from backend.imagery.sink import MosaicSink
from backend.storage.database import make_engine, migrate
from backend.survey.flight.progress import new_run
from backend.survey.flight.run import DroneState, SurveyRun, SurveyState
from backend.survey.planning.schemas import SurveyRequest
from backend.survey.planning.survey import Fleet, plan_survey, summary
from common.geodesy import GeoPoint, LocalFrame
from protocol.photos import CameraIntrinsics, PhotoMeta, PhotoPose
from simulator.outputs.photos import nadir_renderer

LAT, LON = 47.0, 8.0
FRAME = LocalFrame(LAT, LON)
CAMERA = CameraIntrinsics(
    sensor_width_mm=4.8,
    sensor_height_mm=3.6,
    image_width_px=128,
    image_height_px=96,
    focal_length_mm=5.4,
)


def survey() -> SurveyRun:
    ring = [
        list(reversed(FRAME.to_geo(x, y)))
        for x, y in [(0, 0), (300, 0), (300, 200), (0, 200), (0, 0)]
    ]
    request = SurveyRequest.model_validate(
        {
            "area": {"type": "Polygon", "coordinates": [ring]},
            "camera": CAMERA.model_dump() | {"landscape": True},
            "altitude_m": 40,
            "angle_deg": 0,
            "vehicle_ids": ["d0"],
        }
    )
    lat, lon = FRAME.to_geo(-20.0, -30.0)
    run = new_run(
        request,
        summary(
            plan_survey(request, [Fleet("d0", GeoPoint(lat, lon, 500), GeoPoint(lat, lon, 500))])
        ),
    )
    run.state = SurveyState.FLYING
    run.started = 1_000.0
    run.drones[0].state = DroneState.FLYING
    return run


class Sink:
    def __init__(self) -> None:
        self.photos: list[StoredPhoto] = []

    async def add_photo(self, photo: StoredPhoto) -> None:
        self.photos.append(photo)


@pytest.fixture(scope="module")
def migrated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A migrated store, made once: each test works on a copy."""
    path = tmp_path_factory.mktemp("store") / "hub.sqlite"
    engine = make_engine(f"sqlite:///{path}")
    migrate(engine)
    engine.dispose()
    return path


@pytest.fixture
def ingest_for(tmp_path: Path, migrated: Path) -> Callable[..., PhotoIngest]:
    def make(run: SurveyRun, sink: Sink | None = None) -> PhotoIngest:
        shutil.copy(migrated, tmp_path / "hub.sqlite")
        return _ingest(tmp_path, run, sink)

    return make


def _ingest(tmp_path: Path, run: SurveyRun, sink: PhotoSink | None) -> PhotoIngest:
    engine = make_engine(f"sqlite:///{tmp_path / 'hub.sqlite'}")

    async def find(survey_id: str) -> SurveyRun:
        if survey_id != run.id:
            raise NotFound(f"no survey {survey_id}")
        return run

    return PhotoIngest(
        PhotoRepository(engine),
        tmp_path / "photos",
        lambda: [run],
        find,
        margin_m=100.0,
        quota_bytes=10**9,
        sink=sink,
    )


def jpeg(size: tuple[int, int] = (128, 96)) -> bytes:
    out = io.BytesIO()
    Image.effect_noise(size, 50).convert("RGB").save(out, "JPEG")
    return out.getvalue()


def meta_for(
    photo_id: str, data: bytes, east: float = 100.0, north: float = 100.0, **change: object
) -> str:
    lat, lon = FRAME.to_geo(east, north)
    pose = PhotoPose(
        lat=lat, lon=lon, alt_msl=540, alt_rel=40, roll=0, pitch=0, yaw=0, time=1_010.0
    )
    meta = PhotoMeta(photo_id=photo_id, index=1, size_bytes=len(data), pose=pose, camera=CAMERA)
    return meta.model_copy(update=change).model_dump_json()


async def send(
    ingest: PhotoIngest, photo_id: str, data: bytes, meta: str, chunk: int = 1000
) -> str:
    state = None
    for offset in range(0, len(data), chunk):
        state = await ingest.put_chunk(
            "d0", photo_id, offset, data[offset : offset + chunk], meta if offset == 0 else None
        )
    assert state is not None
    return state.state


def test_a_photo_sent_in_chunks_is_stored_once_with_its_survey_and_handed_on(
    tmp_path: Path,
    ingest_for: Callable[..., PhotoIngest],
) -> None:
    run, sink = survey(), Sink()
    ingest = ingest_for(run, sink)
    data = jpeg()

    async def scenario() -> None:
        assert await send(ingest, "p1", data, meta_for("p1", data)) == "stored"
        # again, from the start: idempotent, nothing received twice
        again = await ingest.put_chunk("d0", "p1", 0, data[:1000], meta_for("p1", data))
        assert again.state == "stored"
        assert (await ingest.state("d0", "p1")).received == len(data)

    asyncio.run(scenario())
    stored = tmp_path / "photos" / "d0" / "p1.jpg"
    assert stored.read_bytes() == data
    assert [p.photo_id for p in sink.photos] == ["p1"]
    assert sink.photos[0].survey_id == run.id  # the survey the drone flew at the time
    assert sink.photos[0].path == stored
    assert list((tmp_path / "photos" / ".partial" / "d0").iterdir()) == []


def test_a_cut_upload_resumes_at_the_committed_offset(
    tmp_path: Path, ingest_for: Callable[..., PhotoIngest]
) -> None:
    ingest = ingest_for(survey())
    data = jpeg()

    async def scenario() -> None:
        await ingest.put_chunk("d0", "p2", 0, data[:1500], meta_for("p2", data))
        assert (await ingest.state("d0", "p2")).received == 1500
        with pytest.raises(OffsetMismatch) as mismatch:
            await ingest.put_chunk("d0", "p2", 3000, data[3000:], None)
        assert mismatch.value.received == 1500
        assert (await ingest.put_chunk("d0", "p2", 1500, data[1500:], None)).state == "stored"

    asyncio.run(scenario())
    assert (tmp_path / "photos" / "d0" / "p2.jpg").read_bytes() == data


@pytest.mark.parametrize(
    ("photo", "meta", "code", "status"),
    [
        ("far", {"east": 600.0}, Refusal.FAR_FROM_SURVEY, 422),
        ("unknown", {"survey_id": "feedfeedfeedfeed"}, Refusal.UNKNOWN_SURVEY, 422),
        ("truncated", {}, Refusal.CORRUPT_IMAGE, 422),
        ("garbage", {}, Refusal.CORRUPT_IMAGE, 422),
        ("small", {}, Refusal.WRONG_IMAGE_SIZE, 422),
        (
            "camera",
            {"camera": CAMERA.model_copy(update={"image_width_px": 64})},
            Refusal.WRONG_IMAGE_SIZE,
            422,
        ),
    ],
)
def test_each_refusal_says_why_is_recorded_and_answered_the_same_again(
    tmp_path: Path,
    ingest_for: Callable[..., PhotoIngest],
    photo: str,
    meta: dict[str, object],
    code: Refusal,
    status: int,
) -> None:
    run = survey()
    ingest = ingest_for(run)
    data = {
        "truncated": jpeg()[:-600],
        "garbage": b"\xff\xd8" + bytes(3000),
        "small": jpeg((64, 48)),
    }.get(photo, jpeg())
    where = {k: v for k, v in meta.items() if k in ("east", "north")}
    change = {k: v for k, v in meta.items() if k not in where}
    meta_json = meta_for(photo, data, **where, **change)  # type: ignore[arg-type]

    async def scenario() -> list[Refused]:
        refusals = []
        for _ in range(2):
            with pytest.raises(Refused) as refused:
                await send(ingest, photo, data, meta_json)
            refusals.append(refused.value)
        return refusals

    first, second = asyncio.run(scenario())
    assert first.code is code
    assert first.status == status
    assert second.reason == first.reason
    record = ingest.repository.get("d0", photo)
    assert record is not None
    assert record.state == "refused"
    assert record.reason is not None
    assert record.reason.startswith(code.value)
    assert not (tmp_path / "photos" / "d0" / f"{photo}.jpg").exists()
    if code is not Refusal.UNKNOWN_SURVEY:  # counted with the survey it was checked against
        counted = ingest.repository.counts(run.id)
        assert [(c.state, c.count) for c in counted] == [("refused", 1)]


def test_metadata_without_a_pose_or_over_the_size_limit_is_refused(
    tmp_path: Path, ingest_for: Callable[..., PhotoIngest]
) -> None:
    ingest = ingest_for(survey())
    data = jpeg()
    no_pose = meta_for("np", data).replace('"pose":', '"posed":')
    too_big = meta_for("big", data).replace(f'"size_bytes":{len(data)}', '"size_bytes":999999999')

    async def refusal(photo_id: str, meta: str | None) -> Refused:
        with pytest.raises(Refused) as refused:
            await ingest.put_chunk("d0", photo_id, 0, data[:100], meta)
        return refused.value

    assert asyncio.run(refusal("np", no_pose)).code is Refusal.NO_POSE
    big = asyncio.run(refusal("big", too_big))
    assert (big.code, big.status) == (Refusal.TOO_LARGE, 413)
    assert asyncio.run(refusal("none", None)).code is Refusal.BAD_METADATA


def test_the_export_is_a_zip_opendronemap_takes(
    tmp_path: Path, ingest_for: Callable[..., PhotoIngest]
) -> None:
    run = survey()
    ingest = ingest_for(run)
    photos = {f"p{i}": jpeg() for i in range(3)}

    async def upload() -> None:
        for photo_id, data in photos.items():
            await send(
                ingest, photo_id, data, meta_for(photo_id, data, east=50.0 * int(photo_id[1:]))
            )

    asyncio.run(upload())
    path = write_zip(ingest.repository.of_survey(run.id), tmp_path / "exports")
    with zipfile.ZipFile(path) as archive:
        listed = archive.read("image_list.txt").decode().split()
        assert listed == [f"images/p{i}.jpg" for i in range(3)]
        for name in listed:
            assert archive.read(name) == photos[Path(name).stem]
        geo = archive.read("geo.txt").decode().splitlines()
    assert geo[0] == "EPSG:4326"
    name, lon, lat, *_ = geo[2].split()
    assert name == "p1.jpg"
    assert FRAME.to_local(float(lat), float(lon)) == pytest.approx((50.0, 100.0), abs=0.01)


def test_a_stored_survey_photo_goes_into_the_live_mosaic(tmp_path: Path, migrated: Path) -> None:
    """Through the hub's own sink into a real mosaic: a photo of the simulator's ground,
    rendered from its pose, uploaded in chunks, ends up in the survey's tiles."""
    run = survey()

    async def area_of(survey_id: str) -> dict[str, object] | None:
        return run.request.area.model_dump() if survey_id == run.id else None

    mosaic = MosaicService(tmp_path / "mosaics", area_of)
    shutil.copy(migrated, tmp_path / "hub.sqlite")
    ingest = _ingest(tmp_path, run, MosaicSink(mosaic))
    lat, lon = FRAME.to_geo(150.0, 100.0)
    pose = PhotoPose(
        lat=lat, lon=lon, alt_msl=540.0, alt_rel=40.0, roll=0, pitch=0, yaw=0, time=1_010.0
    )
    data = nadir_renderer(GeoPoint(LAT, LON, 500.0))(pose, CAMERA)
    meta = PhotoMeta(photo_id="m1", index=1, size_bytes=len(data), pose=pose, camera=CAMERA)

    async def scenario() -> None:
        worker = asyncio.create_task(mosaic.run())
        try:
            assert await send(ingest, "m1", data, meta.model_dump_json()) == "stored"
            await asyncio.wait_for(mosaic.idle(), 60)
        finally:
            worker.cancel()

    asyncio.run(scenario())
    progress = mosaic.progress(run.id)
    assert (progress.processed, progress.failed) == (1, 0)
    assert progress.by_vehicle["d0"].processed == 1
    assert progress.max_zoom is not None


def test_a_photo_is_of_the_survey_flown_when_taken_or_else_when_it_arrives(
    tmp_path: Path, ingest_for: Callable[..., PhotoIngest]
) -> None:
    run = survey()
    run.drones[0].finished = 2_000.0
    ingest = ingest_for(run)
    data = jpeg()

    def survey_at(taken: float, arrived: float) -> str | None:
        meta = PhotoMeta.model_validate_json(meta_for("x", data)).model_copy(deep=True)
        meta = meta.model_copy(update={"pose": meta.pose.model_copy(update={"time": taken})})
        found = asyncio.run(ingest.survey_of("d0", meta, now=arrived))
        return None if found is None else found.id

    assert survey_at(1_500.0, 9_000.0) == run.id  # taken in flight, arrived after an outage
    assert survey_at(7_000.0, 1_500.0) == run.id  # a clock running ahead (a sped-up sim)
    assert survey_at(500.0, 9_000.0) is None  # before and long after: no survey
    assert (
        asyncio.run(ingest.survey_of("other", PhotoMeta.model_validate_json(meta_for("y", data))))
        is None
    )


def test_uploads_in_progress_count_in_the_quota_are_capped_and_expire(
    tmp_path: Path, migrated: Path
) -> None:
    """One agent token wrote 2.5 GB of unfinished uploads in 20 s, outside its quota,
    and nothing removed them: an upload now reserves its declared size from its first
    chunk, a vehicle has at most so many at once, and an untouched one expires."""
    shutil.copy(migrated, tmp_path / "hub.sqlite")
    ingest = _ingest(tmp_path, survey(), None)
    data = jpeg()
    ingest.quota_bytes = 3 * len(data)
    ingest.partials = PartialLimits(max_per_vehicle=2, expiry_s=3600.0)

    async def scenario() -> None:
        for photo in ("a", "b"):  # each sends its first chunk only, and stops
            await ingest.put_chunk("d0", photo, 0, data[:100], meta_for(photo, data))
        with pytest.raises(Refused) as busy:
            await ingest.put_chunk("d0", "c", 0, data[:100], meta_for("c", data))
        assert busy.value.code is Refusal.UPLOADS_IN_PROGRESS
        assert busy.value.status == 429
        assert "2 photo uploads in progress" in busy.value.reason
        # The first chunk of one in progress again is not one more.
        await ingest.put_chunk("d0", "a", 0, data[:100], meta_for("a", data))

        ingest.partials = PartialLimits(max_per_vehicle=8, expiry_s=3600.0)
        big = meta_for("c", data, size_bytes=len(data) + 1)
        with pytest.raises(Refused) as over:
            await ingest.put_chunk("d0", "c", 0, data[:100], big)
        assert over.value.code is Refusal.QUOTA
        assert over.value.status == 413
        assert f"{2 * len(data)} reserved by 2 uploads in progress" in over.value.reason
        assert ingest.repository.get("d0", "c") is None  # not recorded: it may pass later

        # Untouched past the expiry, both are removed, and their room is free again.
        assert await ingest.expire_stale(now=time.time() + 3601) == 2
        assert list((tmp_path / "photos" / ".partial" / "d0").iterdir()) == []
        assert await send(ingest, "c", data, meta_for("c", data)) == "stored"

    asyncio.run(scenario())
