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

    def show_magnification(self, value: float, since: float) -> None:
        """The magnification a result is drawn at (its scene's default until the user chose one),
        on the slider and in its label, unless the page moved the slider since the frame began."""
        label = magnification_label(value)
        if self.magnification.label != label:
            self.magnification.label = label
        if self.magnification.value != value and self.magnification.update_timestamp <= since:
            self.magnification.value = value

    def sync(self, sliders, since: float) -> None:
        """Play box and cam-angle sliders (`sliders`: this folder's and the one under the plots)
        in step with the playback clock, except a control the page changed since the frame
        began (`since`): its value is on its way to the loop and must not be overwritten."""
        playing = self.playback.playing
        if self.play.value != playing and self.play.update_timestamp <= since:
            self.play.value = playing
        shown = round(self.playback.angle_deg, 1) % 360.0
        for handle in sliders:
            if abs(handle.value - shown) > 1e-9 and handle.update_timestamp <= since:
                handle.value = shown
