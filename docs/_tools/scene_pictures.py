"""One picture of each built-in scene in the browser explorer, for the README's table of scenes.

For every scene of the package's built-in scene directory (explorer.scene.builtin) this starts
`explorer serve PATH --paused --port 0` in its own process group, opens headless Chromium at
1280x800, sets the cam angle to 20 deg before the valve's highest lift (the gear visibly
displaced, the cursor on the rising flank), waits until the page shows that result (every plot
with tick labels on both axes, the cursor at that angle, the gear drawn) and saves the plots and
the 3D view (the left 896 px, without the control panel) scaled by one half, in 128 colours:
docs/images/scenes/NAME.png, ~50 kB each.

    .venv/bin/python docs/_tools/scene_pictures.py                 # every scene
    .venv/bin/python docs/_tools/scene_pictures.py rocking_cam     # some of them

Needs Playwright and Chromium (/usr/bin/chromium, or CHROMIUM=path). The server and its
children end with their group on every exit path (explorer.core.processes.stop_group).
"""

from __future__ import annotations

import argparse
import io
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from explorer.core.processes import spawn, stop_group  # noqa: E402
from explorer.scene.builtin import builtin_scenes  # noqa: E402

OUT = ROOT / "docs" / "images" / "scenes"
CHROMIUM = Path(os.environ.get("CHROMIUM", "/usr/bin/chromium"))
ARGS = ["--headless=new", "--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--ignore-gpu-blocklist", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run"]
VIEWPORT = {"width": 1280, "height": 800}
CLIP = {"x": 0, "y": 0, "width": 896, "height": 800}  # the plots and the 3D view; not the controls
SCALE = 0.5
COLOURS = 128
WAIT_S = 180.0  # a first start on a loaded machine (the worker process, the first result)
BEFORE_PEAK_DEG = 20.0
ANGLE_TRIES, ANGLE_WAIT_S = 4, 30.0

# every plot drawn with tick labels on both axes, and the cursor series (the last) of the plots
# against cam angle at `angle` (the speed sweep's plots are against rpm; null: any angle)
PLOTS_SHOWN = """(angle) => {
  const charts = Object.values(window.__viserTestpoints?.uplots ?? {}).map(t => t.chart);
  const ticked = c => c.axes.slice(0, 2).every(a => (a._values ?? []).length >= 2);
  const atAngle = c => { const i = c.data[c.data.length - 1].indexOf(1); return i >= 0 && Math.abs(c.data[0][i] - angle) < 1.0; };
  return charts.length > 0 && charts.every(ticked) && (angle === null || charts.some(atAngle));
}"""
GEAR_DRAWN = "() => Object.keys(window.__viserMutable?.nodeRefFromName ?? {}).some(k => k.startsWith('/gear/'))"
TWO_FRAMES = "() => new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(true))))"


def picture_angle(path: Path) -> float:
    """20 deg before the valve's highest lift (rounded to 0.1 deg, the slider's step)."""
    import numpy as np

    from explorer.effects.lift import build_lift
    from explorer.effects.pipeline import simulate
    from explorer.scene.scene import load_scene

    scene = load_scene(path, [])
    columns = simulate(scene, lift=build_lift(scene)).columns
    peak = float(columns["cam_angle_deg"][int(np.argmax(columns["valve_lift_m"]))])
    return round((peak - BEFORE_PEAK_DEG) % 360.0, 1)


def serve(name: str) -> tuple[subprocess.Popen, str]:
    """`explorer serve NAME` on a free port, paused; (process, its address)."""
    proc = spawn([sys.executable, "-m", "explorer", "serve", name, "--port", "0", "--paused"], cwd=ROOT,
                 stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                 env=dict(os.environ, PYTHONUNBUFFERED="1"))
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:  # readline returns at the latest when the server ends
        line = proc.stdout.readline()
        if line.startswith("Valve-Gear Explorer: http://"):
            return proc, line.split()[2]
        if not line and proc.poll() is not None:
            break
    stop_group(proc, grace=2.0)
    raise SystemExit(f"scene_pictures: explorer serve {name} printed no address")


def take(sync_api, name: str, angle: float, profile: Path) -> bytes:
    """The page on `name` at `angle`, as PNG bytes of CLIP."""
    proc, url = serve(name)
    try:
        with sync_api.sync_playwright() as pw:
            context = pw.chromium.launch_persistent_context(
                str(profile), executable_path=str(CHROMIUM), headless=True, args=ARGS, viewport=VIEWPORT,
                timeout=WAIT_S * 1000)
            context.set_default_timeout(WAIT_S * 1000)
            try:
                page = context.new_page()
                page.goto(url)
                page.get_by_text("Connected").first.wait_for()
                page.add_style_tag(content=".mantine-Notification-root { display: none !important; }")
                page.wait_for_function(GEAR_DRAWN)
                # the control panel's Cam angle (the slider under the plots would scroll them)
                field = page.locator("label").filter(has_text=re.compile(r"^Cam angle \[°\]$")).first.locator(
                    "xpath=ancestor::div[contains(@class,'mantine-Flex-root')][1]//input[not(@type='hidden')]").last
                # the first result shown, then the angle (a value typed before the first result
                # can be overwritten by the server's own angle while it starts); a few tries
                page.wait_for_function(PLOTS_SHOWN, arg=None)
                for attempt in range(ANGLE_TRIES):
                    field.fill(f"{angle:g}")
                    field.press("Enter")
                    try:
                        page.wait_for_function(PLOTS_SHOWN, arg=angle, timeout=ANGLE_WAIT_S * 1000)
                        break
                    except sync_api.TimeoutError:
                        if attempt == ANGLE_TRIES - 1:
                            raise
                page.mouse.move(640, 790)  # no hover effects on the plots or the gear
                page.evaluate(TWO_FRAMES)
                return page.screenshot(clip=CLIP)
            finally:
                context.close()
    finally:
        stop_group(proc, grace=5.0)


def small(png: bytes) -> bytes:
    """Scaled by SCALE, COLOURS colours, optimised PNG."""
    from PIL import Image

    image = Image.open(io.BytesIO(png)).convert("RGB")
    image = image.resize((round(image.width * SCALE), round(image.height * SCALE)), Image.LANCZOS)
    out = io.BytesIO()
    image.quantize(COLOURS, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE).save(out, "PNG", optimize=True)
    return out.getvalue()


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("names", nargs="*", help="scene names without .toml (default: every built-in scene)")
    args = parser.parse_args(argv)
    from playwright import sync_api

    scenes = {p.stem: p for p in builtin_scenes()}
    unknown = sorted(set(args.names) - set(scenes))
    if unknown:
        print(f"scene_pictures: not built-in scenes: {', '.join(unknown)}", file=sys.stderr)
        return 2
    OUT.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.names or sorted(scenes):
            started = time.perf_counter()
            angle = picture_angle(scenes[name])
            # by its path: a scene by name reads its data files relative to the working directory
            # (table_demo's measured_lift.csv is not found; explorer.scene.scene.load_scene)
            png = small(take(sync_api, str(scenes[name]), angle, Path(tmp) / name))
            (OUT / f"{name}.png").write_bytes(png)
            print(f"{name:28s} {angle:6.1f} deg  {len(png) / 1024:6.1f} kB  {time.perf_counter() - started:5.1f} s",
                  flush=True)
    total = sum(p.stat().st_size for p in OUT.glob("*.png"))
    print(f"{'total':28s} {total / 2**20:.2f} MB in {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
