"""The photo upload route over real HTTP, with the agent's own uploader: chunks, resume,
idempotence, and each refusal with its reason, counted per vehicle."""

from __future__ import annotations

import asyncio
import io
import json
import os
from collections.abc import Callable
from pathlib import Path

import httpx
import pytest
from PIL import Image

from protocol.photos import CameraIntrinsics, PhotoMeta, PhotoPose
from tests.support.agents import scripted_agent
from tests.support.waiting import poll_until_async
from vehicle_agents.camera.geotag import geotag
from vehicle_agents.camera.queue import PhotoQueue
from vehicle_agents.camera.upload import PhotoUploader

pytestmark = pytest.mark.integration

CAMERA = CameraIntrinsics(
    sensor_width_mm=4.8,
    sensor_height_mm=3.6,
    image_width_px=160,
    image_height_px=120,
    focal_length_mm=5.4,
)
POSE = PhotoPose(
    lat=-35.36, lon=149.16, alt_msl=620, alt_rel=36, roll=0, pitch=0, yaw=0, time=1.7e9
)


def photo(photo_id: str, *, size: tuple[int, int] = (160, 120)) -> tuple[PhotoMeta, bytes]:
    out = io.BytesIO()
    Image.effect_noise(size, 60).convert("RGB").save(out, "JPEG", quality=95)
    data = geotag(out.getvalue(), POSE, CAMERA, model="test")
    return PhotoMeta(
        photo_id=photo_id, index=1, size_bytes=len(data), pose=POSE, camera=CAMERA
    ), data


def upload_all(
    queue: PhotoQueue, hub: str, vehicle: str, token: str
) -> tuple[PhotoUploader, list[str]]:
    """Run the agent's uploader until its queue is empty; it and the events it raised."""
    told: list[str] = []
    uploader = PhotoUploader(
        queue, hub, vehicle, token, lambda text, severity: told.append(text), chunk_bytes=4096
    )

    async def run() -> None:
        task = asyncio.create_task(uploader.run())
        try:
            await poll_until_async(lambda: not len(queue), 60, "the photo queue emptied")
        finally:
            task.cancel()

    asyncio.run(run())
    return uploader, told


def test_the_agents_uploader_sends_resumes_and_is_idempotent(
    hub: str, enrol: Callable[[str], str], admin_api: httpx.Client, tmp_path: Path
) -> None:
    token = enrol("ph_1")
    with scripted_agent(hub, "ph_1", token):
        pass
    queue = PhotoQueue(tmp_path / "onboard", budget_bytes=10**8)
    whole_meta, whole = photo("ph_1-1-00001")
    cut_meta, cut = photo("ph_1-2-00002")
    queue.put(whole_meta, whole)
    queue.put(cut_meta, cut)
    # the second photo's upload was cut after its first chunk
    first = httpx.put(
        f"{hub}/api/v1/vehicles/ph_1/photos/{cut_meta.photo_id}",
        params={"offset": 0},
        content=cut[:5000],
        headers={"Authorization": f"Bearer {token}", "X-Photo-Meta": cut_meta.model_dump_json()},
    )
    assert first.status_code == 200, first.text
    assert first.json() == {"received": 5000, "size": len(cut), "state": "receiving"}

    uploader, _ = upload_all(queue, hub, "ph_1", token)
    assert uploader.stats.uploaded == 2
    assert uploader.stats.resumed == 1
    assert uploader.stats.bytes_sent == len(whole) + len(cut) - 5000  # nothing sent twice
    listed = admin_api.get("/api/v1/vehicles/ph_1/photos").json()
    assert (listed["received"], listed["failed"]) == (2, 0)
    for meta, data in ((whole_meta, whole), (cut_meta, cut)):
        # the `hub` fixture's data folder is this test's tmp_path
        assert (tmp_path / "photos" / "ph_1" / f"{meta.photo_id}.jpg").read_bytes() == data

    # again: the hub has it, and says so without taking a byte
    queue.put(whole_meta, whole)
    again, _ = upload_all(queue, hub, "ph_1", token)
    assert (again.stats.uploaded, again.stats.bytes_sent) == (1, 0)


def test_refusals_say_why_and_are_counted_per_vehicle(
    hub: str, enrol: Callable[[str], str], admin_api: httpx.Client, tmp_path: Path
) -> None:
    token, other = enrol("ph_2"), enrol("ph_3")
    with scripted_agent(hub, "ph_2", token), scripted_agent(hub, "ph_3", other):
        pass
    url = f"{hub}/api/v1/vehicles/ph_2/photos"

    def put(
        photo_id: str, body: bytes, offset: int = 0, meta: str | None = None, bearer: str = token
    ) -> httpx.Response:
        headers = {"Authorization": f"Bearer {bearer}"}
        if meta is not None:
            headers["X-Photo-Meta"] = meta
        return httpx.put(
            f"{url}/{photo_id}", params={"offset": offset}, content=body, headers=headers
        )

    meta, data = photo("a")
    # another vehicle's token: refused by the policy, counted against ph_2
    assert put("a", data, meta=meta.model_dump_json(), bearer=other).status_code == 403
    # no pose
    no_pose = json.loads(meta.model_copy(update={"photo_id": "b"}).model_dump_json())
    del no_pose["pose"]
    answer = put("b", data, meta=json.dumps(no_pose))
    assert answer.status_code == 422
    assert answer.json()["code"] == "no_pose"
    assert "pose" in answer.json()["detail"]
    # a chunk at the wrong offset: the hub's own is in the answer
    meta_c, data_c = photo("c")
    assert put("c", data_c[:3000], meta=meta_c.model_dump_json()).status_code == 200
    wrong = put("c", data_c[5000:], offset=5000)
    assert (wrong.status_code, wrong.json()["received"]) == (409, 3000)
    # a truncated JPEG: the last byte never came, its size declared short
    meta_d, data_d = photo("d")
    short = data_d[:-700]
    meta_d = meta_d.model_copy(update={"size_bytes": len(short)})
    answer = put("d", short, meta=meta_d.model_dump_json())
    assert (answer.status_code, answer.json()["code"]) == (422, "corrupt_image")
    # the wrong size for its camera model
    meta_e, data_e = photo("e", size=(80, 60))
    answer = put("e", data_e, meta=meta_e.model_dump_json())
    assert (answer.status_code, answer.json()["code"]) == (422, "wrong_image_size")
    assert "80x60" in answer.json()["detail"]
    # more than a photo may be, declared: refused before any byte is kept
    meta_f = json.loads(photo("f")[0].model_dump_json()) | {"size_bytes": 41 * 1024 * 1024}
    answer = put("f", data[:100], meta=json.dumps(meta_f))
    assert (answer.status_code, answer.json()["code"]) == (413, "too_large")
    # the agent's uploader drops a refused photo from its queue and tells the operator
    queue = PhotoQueue(tmp_path / "onboard", budget_bytes=10**8)
    queue.put(meta_d.model_copy(update={"photo_id": "g"}), short)
    uploader, told = upload_all(queue, hub, "ph_2", token)
    assert uploader.stats.refused == 1
    assert "corrupt_image" in told[0]

    listed = admin_api.get("/api/v1/vehicles/ph_2/photos").json()
    assert listed["received"] == 0
    assert listed["reasons"] == {
        "other_vehicle": 1,
        "no_pose": 1,
        "corrupt_image": 2,
        "wrong_image_size": 1,
        "too_large": 1,
    }
    # the hub still serves: a good photo after all that
    meta_h, data_h = photo("h")
    assert put("h", data_h, meta=meta_h.model_dump_json()).status_code == 201


def test_a_vehicles_uploads_at_once_are_capped_and_its_agent_waits_its_turn(
    tmp_path: Path,
) -> None:
    """Over real HTTP: a first chunk beyond the vehicle's uploads at once is a 429 with
    the code ``uploads_in_progress``, which the agent's uploader keeps the photo for and
    tries again (a refusal for good would have dropped it); once the stale upload
    expires, the photo goes through."""
    from tests.conftest import ADMIN_PASSWORD, hub_settings
    from tests.support.api import access_token, api_client
    from tests.support.hub_server import running_hub

    settings = hub_settings(tmp_path, photo_uploads_per_vehicle=1)
    with running_hub(settings) as hub:
        with api_client(hub, access_token(hub, "admin", ADMIN_PASSWORD)) as admin:
            token = admin.post("/api/v1/vehicles/ph_2/agent-tokens").json()["token"]
        with scripted_agent(hub, "ph_2", token):
            pass
        auth = {"Authorization": f"Bearer {token}"}
        left_meta, left = photo("ph_2-1-00001")
        started = httpx.put(
            f"{hub}/api/v1/vehicles/ph_2/photos/{left_meta.photo_id}",
            params={"offset": 0},
            content=left[:1000],
            headers=auth | {"X-Photo-Meta": left_meta.model_dump_json()},
        )
        assert started.status_code == 200, started.text
        meta, data = photo("ph_2-2-00002")
        busy = httpx.put(
            f"{hub}/api/v1/vehicles/ph_2/photos/{meta.photo_id}",
            params={"offset": 0},
            content=data[:1000],
            headers=auth | {"X-Photo-Meta": meta.model_dump_json()},
        )
        assert busy.status_code == 429, busy.text
        assert busy.json()["code"] == "uploads_in_progress"

        queue = PhotoQueue(tmp_path / "onboard", budget_bytes=10**8)
        queue.put(meta, data)
        told: list[str] = []
        uploader = PhotoUploader(queue, hub, "ph_2", token, lambda t, s: told.append(t))

        async def wait_then_expire() -> None:
            task = asyncio.create_task(uploader.run())
            try:
                await poll_until_async(
                    lambda: uploader.stats.failures > 0, 30, "a try refused for now"
                )
                assert len(queue) == 1, told  # kept, not dropped for good
                # The left upload goes stale (as if hours passed): the room frees.
                for path in (tmp_path / "photos" / ".partial" / "ph_2").iterdir():
                    os.utime(path, (0, 0))
                await poll_until_async(lambda: not len(queue), 60, "the photo uploaded")
            finally:
                task.cancel()

        asyncio.run(wait_then_expire())
