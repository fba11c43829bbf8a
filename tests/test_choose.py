"""The shortlist of snapshots that may ship (training.choose)."""

from __future__ import annotations

import json
from pathlib import Path

from doctrpp.training.choose import main

KINDS = ("complete", "partial", "none")


def _record(
    step: int, error: float, coherence: float, black: float = 0.0, identity: bool = False
) -> dict:
    record = {"step": step, "map_error_px/all": error}
    if identity:
        record["identity"] = True
    for kind in KINDS:
        record[f"real/coherence_ratio/{kind}"] = coherence
        record[f"real/black_share/{kind}"] = black
    return record


def _run(tmp_path: Path, records: list[dict]) -> Path:
    run_dir = tmp_path / "s1"
    run_dir.mkdir()
    (run_dir / "validation.jsonl").write_text("".join(json.dumps(r) + "\n" for r in records))
    return run_dir


def test_shortlist_keeps_near_lowest_error_orders_by_coherence(tmp_path, capsys):
    run_dir = _run(
        tmp_path,
        [
            _record(0, 38.0, 1.0, identity=True),
            _record(250, 12.0, 1.10),
            _record(500, 11.8, 1.05),
            _record(750, 11.0, 1.20, black=0.2),  # lowest error, but too much black
            _record(1000, 12.5, 1.30),  # beyond the margin
        ],
    )
    assert main([str(run_dir), "--margin", "0.3"]) == 0
    table = capsys.readouterr().out
    steps = [line.split("|")[2].strip() for line in table.splitlines() if line.startswith("| s1 ")]
    assert steps == ["250", "500"]


def test_missing_run_is_a_clear_error(tmp_path, capsys):
    assert main([str(tmp_path / "nope")]) == 2
    assert "no such file" in capsys.readouterr().err


def test_rescore_commands_compare_with_the_shipped_default(tmp_path, capsys):
    run_dir = _run(tmp_path, [_record(250, 12.0, 1.10)])
    (run_dir / "snapshots").mkdir()
    (run_dir / "snapshots" / "step0000250.pt").write_bytes(b"")
    assert main([str(run_dir)]) == 0
    commands = [line for line in capsys.readouterr().out.splitlines() if "training.score" in line]
    assert len(commands) == 2
    for command in commands:  # the default first: the paired lines compare with it
        assert "export/weights/doctrpp_default.pt " in command and "step0000250.pt" in command
        assert command.index("doctrpp_default.pt") < command.index("step0000250.pt")
        assert "--validation-start 48 --validation-size 192" in command
    assert commands[1].endswith("--flip-average --line-alignment")


def test_cross_shot_agreement_orders_the_shortlist_where_logged(tmp_path, capsys):
    records = [_record(250, 12.0, 1.30), _record(500, 11.9, 1.05)]
    records[0]["real/cross_shot_ms_ssim"] = 0.44
    records[1]["real/cross_shot_ms_ssim"] = 0.47  # lower coherence, better agreement
    run_dir = _run(tmp_path, records)
    (run_dir / "snapshots").mkdir()
    (run_dir / "snapshots" / "step0000500.pt").write_bytes(b"")
    assert main([str(run_dir)]) == 0
    out = capsys.readouterr().out
    steps = [line.split("|")[2].strip() for line in out.splitlines() if line.startswith("| s1 ")]
    assert steps == ["500", "250"]
    assert "| 0.4700 |" in out
    cross_shot = [line for line in out.splitlines() if "training.cross_shot" in line]
    assert len(cross_shot) == 1 and "doctrpp_default.pt " in cross_shot[0]
