"""The whole pipeline, not only inference: `doctrpp rectify` on big photos in a fresh process.

- throughput: images/s over a folder of 12 MP JPEG photos (decode, inference, map, remap,
  PNG encode), at several `--jobs` with the default flip averaging (two model runs per
  photo), and at the first `--jobs` with `--no-flip-average` (one run);
- memory: peak RSS of rectifying one 108 MP photo, with and without `--save-map`.
Photos are real document photos (`--photos`, else generated crops) scaled up to the size.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

MEGAPIXELS_THROUGHPUT = 12
MEGAPIXELS_HUGE = 108

# Runs `doctrpp rectify` in this process and prints its peak resident memory (VmHWM).
_PROBE = """
import json, sys
from doctrpp.cli import main
code = main(sys.argv[1:])
with open("/proc/self/status") as f:
    peak_kb = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
print(json.dumps({"code": code, "peak_kb": peak_kb}))
"""


def big_photo(source: np.ndarray, megapixels: float) -> np.ndarray:
    """`source` resized (cubic) to about `megapixels`, keeping its aspect (4:3 if square)."""
    h, w = source.shape[:2]
    aspect = w / h if abs(w - h) > 2 else 4 / 3
    height = int(round(np.sqrt(megapixels * 1e6 / aspect)))
    return cv2.resize(source, (int(round(height * aspect)), height), interpolation=cv2.INTER_CUBIC)


def source_photos(folder: Path | None, count: int) -> list[np.ndarray]:
    if folder:
        from doctrpp.runtime.imageio import image_files, read_image

        files = image_files(folder)
        return [read_image(p)[:, :, :3] for p in files[:count]]
    from doctrpp.udir.sample import generate

    return [generate(5_000_000 + i, "complete", size=900).image for i in range(count)]


def run_rectify(args: list[str]) -> tuple[float, float]:
    """(wall seconds, peak RSS MB) of `doctrpp rectify ARGS` in a fresh process."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", _PROBE, "rectify", *args],
        capture_output=True,
        text=True,
        timeout=1800,
        cwd=tempfile.gettempdir(),  # not a source checkout
    )
    wall = time.perf_counter() - start
    last = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
    if done.returncode != 0 or not last.startswith("{"):
        raise RuntimeError(f"rectify failed: {done.stderr.strip().splitlines()[-1:]}")
    result = json.loads(last)
    if result["code"] != 0:
        raise RuntimeError(f"rectify exited {result['code']}: {done.stderr.strip()[-300:]}")
    return wall, result["peak_kb"] / 1024


def pipeline_report(
    model: Path,
    photos: Path | None,
    count: int = 6,
    jobs: tuple[int, ...] = (1, 2),
    threads: int = 2,
    megapixels: tuple[float, float] = (MEGAPIXELS_THROUGHPUT, MEGAPIXELS_HUGE),
) -> dict:
    model = Path(model).resolve()  # rectify runs from a temporary folder
    report: dict = {"model": str(model), "threads": threads, "throughput": [], "memory": []}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "photos12"
        folder.mkdir()
        sources = source_photos(photos, count)
        for i, source in enumerate(sources):
            image = big_photo(source, megapixels[0])
            cv2.imwrite(str(folder / f"p{i:02d}.jpg"), image, [cv2.IMWRITE_JPEG_QUALITY, 92])
        report["photo_size"] = f"{image.shape[1]}x{image.shape[0]} JPEG q92"
        runs = [(j, True) for j in jobs] + [(jobs[0], False)]
        for j, flip_average in runs:
            out = Path(tmp) / f"out{j}{'' if flip_average else '_one_run'}"
            args = [str(folder), "--model", str(model), "-o", str(out), "--jobs", str(j)]
            args += ["--threads", str(threads)] + ([] if flip_average else ["--no-flip-average"])
            wall, rss = run_rectify(args)
            report["throughput"].append(
                {
                    "jobs": j,
                    "flip_average": flip_average,
                    "images": len(sources),
                    "seconds": wall,
                    "images_per_s": len(sources) / wall,
                    "peak_rss_mb": rss,
                }
            )
        huge = big_photo(sources[0], megapixels[1])
        huge_path = Path(tmp) / "huge.jpg"
        cv2.imwrite(str(huge_path), huge, [cv2.IMWRITE_JPEG_QUALITY, 92])
        report["huge_size"] = f"{huge.shape[1]}x{huge.shape[0]}"
        del huge
        for save_map in (False, True):
            out = Path(tmp) / f"huge_out{int(save_map)}"
            args = [
                str(huge_path),
                "--model",
                str(model),
                "-o",
                str(out),
                "--threads",
                str(threads),
            ]
            wall, rss = run_rectify(args + (["--save-map"] if save_map else []))
            report["memory"].append({"save_map": save_map, "seconds": wall, "peak_rss_mb": rss})
    return report


def pipeline_markdown(report: dict) -> list[str]:
    lines = [
        "",
        "## Whole pipeline (`doctrpp rectify`, fresh process)",
        "",
        f"Model {Path(report['model']).name}, {report['threads']} inference threads per image; "
        f"{report['photo_size']} photos (decode, inference, map, remap, PNG encode; process "
        "start included).",
        "",
        "| jobs | flip averaging | images | seconds | images/s | peak RSS MB |",
        "|---|---|---|---|---|---|",
    ]
    for row in report["throughput"]:
        flip = "yes (default)" if row.get("flip_average", False) else "no (one run)"
        lines.append(
            f"| {row['jobs']} | {flip} | {row['images']} | {row['seconds']:.1f} | "
            f"{row['images_per_s']:.2f} | {row['peak_rss_mb']:.0f} |"
        )
    lines += [
        "",
        f"One {report['huge_size']} photo:",
        "",
        "| --save-map | seconds | peak RSS MB |",
        "|---|---|---|",
    ]
    for row in report["memory"]:
        lines.append(
            f"| {'yes' if row['save_map'] else 'no'} | {row['seconds']:.1f} | "
            f"{row['peak_rss_mb']:.0f} |"
        )
    return lines
