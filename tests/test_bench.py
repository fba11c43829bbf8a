"""`doctrpp bench` writes a complete report (tiny models, few runs)."""

from __future__ import annotations

import json

from doctrpp.cli import main
from doctrpp.quantize.calibration import generated_inputs
from doctrpp.quantize.presets import preset_by_name
from doctrpp.quantize.quantize import quantise


def test_bench_report(tiny_onnx, tmp_path):
    int8 = tmp_path / "tiny_int8.onnx"
    quantise(tiny_onnx, int8, preset_by_name("static-weights"), list(generated_inputs(3)))
    out = tmp_path / "report"
    code = main(
        [
            "bench",
            "--models",
            str(tiny_onnx),
            str(int8),
            "--out",
            str(out),
            "--runs",
            "2",
            "--per-kind",
            "1",
            "--no-peers",
        ]
    )
    assert code == 0
    report = json.loads((out / "report.json").read_text())
    fp32, q = report["models"]
    assert fp32["precision"] == "fp32" and q["precision"] == "int8"
    assert set(fp32["latency"]) == {"1", "2"} and fp32["latency_ratio"] == 1.0
    assert fp32["accuracy"]["partial"]["drift_max_px"] == 0.0
    assert "gt_map_error_px" in q["accuracy"]["none"]
    assert q["peak_rss_mb"] > 10
    assert report["environment"]["allocator"]
    checks = {t["check"] for t in report["targets"]}
    assert {"max drift px (generated crops)", "latency vs reference, 1 thread", "file MB"} <= checks
    assert set(report["untouched"]) == {"complete", "partial", "none"}
    markdown = (out / "report.md").read_text()
    assert "| tiny_int8.onnx | onnx | int8 |" in markdown
    assert "allocator" in markdown
    assert "| untouched input | none |" in markdown
    assert "## Real-photo crops (reference-free)" in markdown  # scikit-image's photos
    assert 0 <= fp32["accuracy"]["real none"]["black_share"] <= 1
    assert report["peers"] == []
    assert "- phone:" in markdown and "- CPU server:" in markdown
    assert (out / "latency.png").is_file() and (out / "drift_vs_latency.png").is_file()


def test_bench_errors(tmp_path):
    assert main(["bench", "--models", str(tmp_path / "absent.onnx"), "--out", str(tmp_path)]) == 2


def test_whole_pipeline_section(tiny_onnx, tmp_path, monkeypatch):
    """bench --pipeline: images/s at each --jobs and peak RSS on one big photo (small here);
    a model path relative to the caller's folder works (rectify runs elsewhere)."""
    from pathlib import Path

    from doctrpp.benchmarks.pipeline import big_photo, pipeline_markdown, pipeline_report

    monkeypatch.chdir(tiny_onnx.parent)
    report = pipeline_report(
        Path(tiny_onnx.name), None, count=2, jobs=(1, 2), threads=1, megapixels=(0.3, 1.0)
    )
    runs = [(row["jobs"], row["flip_average"]) for row in report["throughput"]]
    assert runs == [(1, True), (2, True), (1, False)]
    assert all(row["images_per_s"] > 0 and row["peak_rss_mb"] > 10 for row in report["throughput"])
    assert [row["save_map"] for row in report["memory"]] == [False, True]
    text = "\n".join(pipeline_markdown(report))
    assert "images/s" in text and "peak RSS MB" in text
    import numpy as np

    assert abs(big_photo(np.zeros((300, 200, 3), np.uint8), 12).size / 3 / 12e6 - 1) < 0.01


def test_sheets_and_int8_recipe_inputs(tiny_checkpoint, tmp_path):
    import cv2

    from doctrpp.benchmarks.int8_recipes import calibration_set
    from doctrpp.training.sheets import sheet
    from doctrpp.udir.sample import generate

    photos = tmp_path / "photos"
    photos.mkdir()
    for i in range(3):
        cv2.imwrite(str(photos / f"p{i}.jpg"), generate(i, "complete", size=320).image)
    image = sheet([tiny_checkpoint, tiny_checkpoint], ["a", "b"], photos, "none", 2, 64)
    assert image.shape == (128, 192, 3)
    inputs = calibration_set("mixed", sorted(photos.iterdir()), 4)
    assert len(inputs) == 4 and inputs[0].shape == (1, 3, 288, 288)


def test_recommendations_name_a_slow_int8_file_once():
    from doctrpp.benchmarks.report import recommendations

    def model(name, fmt, precision, ms, ratio):
        accuracy = {"complete": {"drift_mean_px": 0.1, "drift_max_px": 0.5}}
        latency = {"2": {"median_ms": ms, "p90_ms": ms}}
        return {
            "name": name,
            "format": fmt,
            "precision": precision,
            "file_mb": 1.0,
            "latency": latency,
            "latency_ratio": ratio,
            "accuracy": accuracy,
        }

    report = {
        "models": [
            model("ref.onnx", "onnx", "fp32", 50.0, 1.0),
            model("half.tflite", "tflite", "fp16", 41.0, 0.82),
            model("q.tflite", "tflite", "int8", 40.0, 0.8),
            model("q.onnx", "onnx", "int8", 48.0, 0.96),
        ]
    }
    lines = recommendations(report)
    assert lines[0].startswith("phone: **q.tflite**") and "over the int8 speed target" in lines[0]
    assert lines[-1].startswith("faithful but not fast enough") and "q.onnx" in lines[-1]
    assert "q.tflite" not in lines[-1]


def _shots(folder, documents: int = 2) -> None:
    """`documents` pairs of small gray pages with dark bars, the second shot tilted."""
    import cv2
    import numpy as np

    folder.mkdir()
    for document in range(1, documents + 1):
        page = np.full((160, 120, 3), 235, np.uint8)
        for row in range(10, 150, 12):
            page[row : row + 4, 8 + document : 100] = 40
        tilted = cv2.warpAffine(page, cv2.getRotationMatrix2D((60, 80), 3, 1.0), (120, 160))
        cv2.imwrite(str(folder / f"{document}_1.png"), page)
        cv2.imwrite(str(folder / f"{document}_2.png"), tilted)


def test_bench_scores_cross_shot_agreement_of_photo_pairs(tiny_onnx, tmp_path):
    photos, out = tmp_path / "photos", tmp_path / "report"
    _shots(photos)
    args = ["bench", "--models", str(tiny_onnx), "--out", str(out), "--runs", "1"]
    args += ["--per-kind", "0", "--no-rss", "--no-peers", "--threads", "1", "--photos", str(photos)]
    assert main(args) == 0
    section = json.loads((out / "report.json").read_text())["cross_shot"]
    assert section["documents"] == 2
    untouched, model = section["rows"]
    assert untouched["name"] == "untouched photos" and model["name"] == tiny_onnx.name
    assert 0 < untouched["cross_shot_ms_ssim"] < 1 and 0 < model["cross_shot_ms_ssim"] <= 1
    assert untouched["paired_against"] == tiny_onnx.name and "paired_ms_ssim" not in model
    markdown = (out / "report.md").read_text()
    assert "## Real photos: cross-shot agreement" in markdown
    assert f"| {tiny_onnx.name} | " in markdown.split("cross-shot agreement")[1]
    assert (out / "cross_shot_vs_latency.png").is_file()
    off = tmp_path / "off"
    assert main([*args[:4], str(off), *args[5:], "--cross-shot-pairs", "0"]) == 0
    assert json.loads((off / "report.json").read_text())["cross_shot"] is None


def test_bench_refuses_a_single_cross_shot_pair(tiny_onnx, tmp_path, capsys):
    args = ["bench", "--models", str(tiny_onnx), "--out", str(tmp_path / "r")]
    assert main([*args, "--cross-shot-pairs", "1"]) == 2
    assert "--cross-shot-pairs must be 0 (off) or at least 2" in capsys.readouterr().err


def test_bench_names_an_unreadable_photo_in_one_line(tiny_onnx, tmp_path, capsys):
    photos = tmp_path / "photos"
    _shots(photos)
    (photos / "2_2.png").write_bytes(b"not a png")
    args = ["bench", "--models", str(tiny_onnx), "--out", str(tmp_path / "r"), "--runs", "1"]
    args += ["--per-kind", "0", "--no-rss", "--no-peers", "--threads", "1", "--photos", str(photos)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == f"doctrpp bench: error: {photos / '2_2.png'}: not a readable image"
    assert not (tmp_path / "r").exists()


def test_bench_reads_the_load_average_before_its_own_work(tiny_onnx, tmp_path, monkeypatch):
    """The report's load warning is about other work: it must not see the bench's own."""
    from doctrpp.benchmarks import bench, environment

    busy = []  # the load average rises once the bench's own work has begun
    real_accuracy = bench.accuracy
    monkeypatch.setattr(bench, "accuracy", lambda *a: busy.append(1) or real_accuracy(*a))
    monkeypatch.setattr(environment, "load_average", lambda: 9.0 if busy else 0.1)
    out = tmp_path / "r"
    args = ["bench", "--models", str(tiny_onnx), "--out", str(out), "--runs", "1"]
    assert main([*args, "--per-kind", "0", "--no-peers", "--no-rss"]) == 0
    assert json.loads((out / "report.json").read_text())["load_average"] == 0.1
    assert "load average" not in (out / "report.md").read_text()
