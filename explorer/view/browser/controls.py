"""The Playback folder: Play, Speed, the cam-angle slider and the magnification, and keeping them
(and the slider under the plots) in step with the playback clock."""

from __future__ import annotations

from .model import SPEEDS, Playback
from .requests import Magnified, Played, Scrubbed, SpeedChosen, wire

MAGNIFICATION_RANGE = (1.0, 50.0)
# A scene opens at its drawing's default (explorer.view.parts.default_magnification: x20 for a
# train of masses, x1 else) until the user moves the slider; the label says what is drawn.
MAGNIFICATION_HINT = ("enlarges the lash gap and each mass's deviation from rigid motion (the valve; a train's "
                      "lifter, pushrod, rocker or finger and the adjuster's plunger)")


def magnification_label(value: float) -> str:
    return f"Magnification ×{value:g}"
SCRUB_HINT = "scrub: pauses the animation at this angle"


class PlaybackControls:
    """The playback clock (`playback`, model.Playback) and its controls."""

    def __init__(self, gui, inbox, echo, playing: bool):
        self.playback = Playback(playing=playing)
        self.inbox = inbox  # the loop writes a control only when no page's value is on its way
        self.speed_chosen = False  # the user chose a speed: a new scene keeps it
        with gui.add_folder("Playback"):
            self.play = gui.add_checkbox("Play", initial_value=playing, hint="play / pause the animation")
            self.speed = gui.add_dropdown("Speed", [label for label, _ in SPEEDS], initial_value="1/100",
                                          hint="playback speed relative to the real camshaft speed")
            self.angle = gui.add_slider("Cam angle [°]", min=0.0, max=360.0, step=0.1, initial_value=0.0,
                                        hint=SCRUB_HINT)
            self.magnification = gui.add_slider(magnification_label(1.0), min=MAGNIFICATION_RANGE[0],
                                                max=MAGNIFICATION_RANGE[1], step=1.0, initial_value=1.0,
                                                hint=MAGNIFICATION_HINT)
        wire(self.play, inbox, lambda v, page, at: Played(bool(v)), echo)
        wire(self.speed, inbox, lambda v, page, at: SpeedChosen(str(v)), echo)
        wire(self.angle, inbox, lambda v, page, at: Scrubbed(float(v)), echo)
        wire(self.magnification, inbox, lambda v, page, at: Magnified(float(v)), echo)

    def chose_speed(self, label: str) -> None:
        speed = dict(SPEEDS).get(label)
        if speed is not None:
            self.playback.speed = speed
            self.speed_chosen = True

    def scrub(self, angle: float) -> None:
        self.playback.angle_deg = angle % 360.0
        self.playback.playing = False

    def default_speed(self, label: str) -> None:
        """The speed a scene opens with (model.default_speed), unless the user chose one."""
        if not self.speed_chosen:
            self.playback.speed = dict(SPEEDS)[label]
            if self.speed.value != label:
                self.speed.value = label

    def show_magnification(self, value: float) -> None:
        """The magnification a result is drawn at (its scene's default until the user chose one),
        on the slider and in its label, unless a page's move of the slider is on its way."""
        label = magnification_label(value)
        if self.magnification.label != label:
            self.magnification.label = label
        self.inbox.write(self.magnification, value)

    def sync(self, sliders) -> None:
        """Play box and cam-angle sliders (`sliders`: this folder's and the one under the plots)
        in step with the playback clock, except a control whose value from a page is on its way
        to the loop (requests.Inbox.write): it must not be overwritten."""
        self.inbox.write(self.play, self.playback.playing)
        shown = round(self.playback.angle_deg, 1) % 360.0
        for handle in sliders:
            if abs(handle.value - shown) > 1e-9:
                self.inbox.write(handle, shown)
