"""Benchmark: what one frame of the 3D view costs a browser that draws in software, simplified meshes against full.

    python scripts/bench_viewer_frame.py            # 40 frames per page, 3 rounds
    python scripts/bench_viewer_frame.py --json     # JSON last line

The same scene (``teachbot view``'s: prepare-lunch in kitchen-1, seed 0) is exported twice as a
self-contained page: once with the viewer's meshes as shipped (each OBJ mesh without texture coordinates
simplified to bullet_world.viewer.meshes.VIEWER_TRIANGLES triangles) and once with the full meshes (the
Panda's ~100,000 triangles); the simplified page is also drawn as the web page draws it in software, with
diffuse (Lambert) materials (dialog/web/static/diffuse.js). Headless Chromium, with SwiftShader (software
WebGL, as on a machine without a GPU), draws each page's scene ``--frames`` times in a row, waiting for
each frame to finish (a pixel read back after each); the rounds alternate the pages so that a change in the
machine's load falls on all. Printed: triangles drawn per frame and milliseconds per frame for each, and
the ratios of full and diffuse to simplified.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bullet_world.viewer import meshes  # noqa: E402
from bullet_world.viewer.snapshot import CHROMIUM_FLAGS, find_chromium  # noqa: E402

DIFFUSE_JS = ROOT / "dialog" / "web" / "static" / "diffuse.js"

DRAW = """async ([frames, diffuse]) => {
  await new Promise((done) => { const wait = () => (viewer && viewer.scene && viewer.scene.children.length)
    ? done() : setTimeout(wait, 50); wait(); });
  const renderer = viewer.renderer, gl = renderer.getContext(), pixel = new Uint8Array(4);
  // reading a pixel back waits until the frame is really drawn (gl.finish may return at once)
  const draw = () => {
    if (diffuse) { diffuseOnly(viewer.scene, MeshCat.THREE); }
    renderer.render(viewer.scene, viewer.camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
  };
  draw();
  const triangles = renderer.info.render.triangles, times = [];
  for (let i = 0; i < frames; i++) {
    const start = performance.now();
    draw();
    times.push(performance.now() - start);
  }
  return {triangles, times};
}"""


def export_scene(path: Path, triangles: int | None) -> None:
    """``teachbot view --export`` of the benchmark's scene, with meshes of at most ``triangles`` (None: full)."""
    from bullet_world.viewer.mirror import Viewer
    from dialog.environment import SimulatedKitchen
    from dialog.manager import episode_generators

    meshes.VIEWER_TRIANGLES = triangles
    environment = SimulatedKitchen(task="prepare-lunch", kitchen="kitchen-1", seed=0)
    try:
        scene = environment.next_scene(episode_generators(0)["scenes"])
        viewer = Viewer(environment.world, record=True)
        try:
            viewer.start_recording()
            viewer.on_scene(scene)
            viewer.export_html(path, title="bench_viewer_frame")
        finally:
            viewer.close()
    finally:
        environment.close()


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=40, help="frames drawn per page and round (default 40)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds, alternating the pages (default 3)")
    parser.add_argument("--json", action="store_true", help="end with one JSON line")
    args = parser.parse_args(argv)
    if args.frames < 1 or args.rounds < 1:
        parser.error("--frames and --rounds must be 1 or more")
    chromium = find_chromium()
    if chromium is None:
        print("error: needs Chromium at /usr/bin/chromium (apt-get install -y chromium)", file=sys.stderr)
        return 2
    from playwright.sync_api import sync_playwright

    shipped = meshes.VIEWER_TRIANGLES
    with tempfile.TemporaryDirectory() as folder:
        pages = {"simplified": Path(folder) / "simplified.html", "full": Path(folder) / "full.html"}
        export_scene(pages["simplified"], shipped)
        pages["diffuse"] = pages["simplified"]
        export_scene(pages["full"], None)
        meshes.VIEWER_TRIANGLES = shipped
        results: dict[str, dict] = {name: {"times": []} for name in pages}
        with sync_playwright() as driver:
            browser = driver.chromium.launch(executable_path=chromium, args=list(CHROMIUM_FLAGS))
            try:
                for _ in range(args.rounds):
                    for name, path in pages.items():
                        page = browser.new_page(viewport={"width": 900, "height": 600})
                        page.goto(path.as_uri(), timeout=600_000)  # the full page is large: slow to parse
                        page.set_default_timeout(600_000)
                        page.add_script_tag(path=str(DIFFUSE_JS))
                        drawn = page.evaluate(DRAW, [args.frames, name == "diffuse"])
                        results[name]["triangles"] = drawn["triangles"]
                        results[name]["times"] += drawn["times"]
                        page.close()
            finally:
                browser.close()
    summary: dict = {"frames": args.frames * args.rounds, "viewer_triangles": shipped,
                     "load_average": round(os.getloadavg()[0], 2)}
    for name, result in results.items():
        times = np.array(result["times"])
        summary[name] = {"triangles": int(result["triangles"]),
                         "ms_per_frame_median": round(float(np.median(times)), 1),
                         "ms_per_frame_p95": round(float(np.percentile(times, 95)), 1)}
    summary["ratio_median"] = round(summary["full"]["ms_per_frame_median"]
                                    / summary["simplified"]["ms_per_frame_median"], 2)
    summary["diffuse_ratio_median"] = round(summary["diffuse"]["ms_per_frame_median"]
                                            / summary["simplified"]["ms_per_frame_median"], 2)
    for name in pages:
        row = summary[name]
        print(f"{name:>10}: {row['triangles']:>7} triangles, {row['ms_per_frame_median']:.1f} ms per frame (median), "
              f"p95 {row['ms_per_frame_p95']:.1f} ms")
    print(f"full / simplified: {summary['ratio_median']:.2f}x per frame (median of {summary['frames']} frames each; "
          f"load average {summary['load_average']})")
    print(f"diffuse / simplified: {summary['diffuse_ratio_median']:.2f}x per frame")
    if args.json:
        print(json.dumps(summary))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
