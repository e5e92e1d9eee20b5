"""Where each page's camera looks: the whole revolution of the gear framed for the page's canvas,
when a scene loads and whenever the canvas changes shape, until someone moves the camera."""

from __future__ import annotations

import math

import numpy as np

from .. import parts as meshes

# A narrower lens than three.js' 75 degrees (less distortion of a machine drawing), and until a
# page reports its canvas, a canvas a little taller than wide, as the 3D view between the two side
# panels of a laptop-sized window is.
CAMERA_FOV = math.radians(45.0)
ASSUMED_ASPECT = 0.75


def camera_frame(prepared, aspect: float = ASSUMED_ASPECT) -> meshes.CameraFrame:
    """The camera that sees every part over the whole revolution, in a canvas of `aspect`."""
    lo, hi = prepared.bounds
    return meshes.frame_bounds(lo, hi, fov=CAMERA_FOV, aspect=aspect)


def same_camera(position, look_at, frame) -> bool:
    reach = float(np.linalg.norm(np.subtract(frame.position, frame.look_at)))
    return bool(np.allclose(position, frame.position, atol=1e-4 * reach)
                and np.allclose(look_at, frame.look_at, atol=1e-4 * reach))


class Cameras:
    """The initial camera (new pages, "Reset View") and each page's: `aim` frames a scene,
    `pending` are the pages to frame again at the next frame (connected, or a canvas resized)."""

    def __init__(self, server, client=None):
        self.server, self.client = server, client
        self.camera: meshes.CameraFrame | None = None  # the initial camera
        self.client_cameras: dict[int, meshes.CameraFrame] = {}  # what each page was last aimed at
        self.earlier_aims: dict[int, tuple] = {}  # and the aims before that, newest last
        self.pending: set[int] = set()  # pages to frame at the next frame

    def clients(self) -> dict:
        """The pages the app shows itself on."""
        if self.client is not None:
            return {self.client.client_id: self.client}
        return self.server.get_clients()

    def connected(self, client) -> None:
        self.pending.add(client.client_id)

    def left(self, client_id: int) -> None:
        self.pending.discard(client_id)
        self.client_cameras.pop(client_id, None)
        self.earlier_aims.pop(client_id, None)

    def aim(self, prepared) -> None:
        """Frame a new scene: the initial camera and every page's own, each for its canvas."""
        frame = camera_frame(prepared)
        if self.client is None:  # the initial camera is the server's: only a shared app sets it
            initial = self.server.initial_camera
            initial.fov = frame.fov
            initial.up = frame.up
            initial.position = frame.position
            initial.look_at = frame.look_at
        self.camera = frame
        for client in self.clients().values():
            self.aim_client(client, prepared)

    def aim_pending(self, prepared) -> None:
        clients = self.clients() if self.pending else {}
        pending, self.pending = self.pending, set()
        for client_id in pending:
            if client_id in clients:
                self.aim_client(clients[client_id], prepared)

    def aim_client(self, client, prepared) -> None:
        camera = client.camera
        try:
            aspect = camera.aspect
        except (AssertionError, ZeroDivisionError):
            # no camera report yet (viser counts a page as connected only after one): it
            # starts from the initial camera, and connecting brings it here
            return
        frame = camera_frame(prepared, aspect if math.isfinite(aspect) and aspect > 0.0 else ASSUMED_ASPECT)
        camera.fov = frame.fov
        camera.up_direction = frame.up
        camera.position = frame.position  # moves look_at along; set it after (viser's rule)
        camera.look_at = frame.look_at
        previous = self.client_cameras.get(client.client_id)
        if previous is not None:  # the last few aims: a late report may still show one of them
            self.earlier_aims[client.client_id] = (*self.earlier_aims.get(client.client_id, ())[-3:], previous)
        self.client_cameras[client.client_id] = frame

    def reported(self, camera) -> None:
        """A page reports its camera after every change. Its canvas often changes shape after
        the first report (the side panels dock) and whenever the window is resized: frame the
        gear again for the new shape, as long as the camera is still where it was put (a
        camera someone has moved is theirs)."""
        client_id = camera.client.client_id
        frame = self.client_cameras.get(client_id)
        if frame is None:
            return
        try:
            aspect = camera.aspect
            position, look_at = np.asarray(camera.position), np.asarray(camera.look_at)
        except (AssertionError, ZeroDivisionError):
            return
        # Untouched: the page shows a camera we put there, the last aim or one before it (the
        # initial camera, an earlier aim): on a loaded machine a page's report can cross our newest
        # aim on the wire, and such a late report is not the user moving the camera.
        placed = (frame, *self.earlier_aims.get(client_id, ()), *((self.camera,) if self.camera is not None else ()))
        untouched = any(same_camera(position, look_at, p) for p in placed)
        if untouched and math.isfinite(aspect) and abs(aspect - frame.aspect) > 0.01 * frame.aspect:
            self.pending.add(client_id)
