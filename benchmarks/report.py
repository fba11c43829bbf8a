"""Writing the benchmark record as report.json, report.md and PNG plots."""

from __future__ import annotations

import json
from pathlib import Path

from doctrpp.files import write_bytes_atomically

KINDS = ("complete", "partial", "none", "photo")


def _fmt(value, digits: int = 3) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def markdown(report: dict) -> str:
    env = report["environment"]
    lines = [
        "# doctrpp-edge benchmark",
        "",
        f"- machine: {env['cpu']}, {env['cores']} cores; {env['platform']}; Python {env['python']}",
        "- packages: " + ", ".join(f"{k} {v}" for k, v in env["packages"].items()),
        f"- allocator: {env['allocator']}",
        f"- latency: median and p90 of {report['settings']['runs']} runs after warm-up, all "
        "models interleaved round by round in one process; onnxruntime CPU provider",
        f"- accuracy inputs: {report['settings']['probes']}; reference model: "
        f"{report['settings']['reference']}",
        f"- weights: {report['settings']['weights']}",
        *([f"- note: {report['settings']['note']}"] if report["settings"].get("note") else []),
        "",
        "## Speed and size",
        "",
        "| model | format | precision | MB | 1 thread median / p90 ms | FPS | 2 threads median / "
        "p90 ms | FPS | vs reference (2 thr) | peak RSS MB |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for m in report["models"]:
        one, two = m["latency"].get("1"), m["latency"].get("2")
        lines.append(
            f"| {m['name']} | {m['format']} | {m['precision']} | {m['file_mb']:.1f} | "
            f"{_fmt(one and one['median_ms'], 0)} / {_fmt(one and one['p90_ms'], 0)} | "
            f"{_fmt(one and one['fps'], 2)} | {_fmt(two and two['median_ms'], 0)} / "
            f"{_fmt(two and two['p90_ms'], 0)} | {_fmt(two and two['fps'], 2)} | "
            f"{_fmt(m.get('latency_ratio'), 2)}x | {_fmt(m.get('peak_rss_mb'), 0)} |"
        )
    for extra in report.get("extra_rows", []):
        lines.append(
            f"| {extra['name']} | {extra['format']} | {extra['precision']} | – | – | – | "
            f"{_fmt(extra['median_ms'], 0)} / {_fmt(extra['p90_ms'], 0)} | "
            f"{_fmt(1000 / extra['median_ms'], 2)} | {_fmt(extra.get('latency_ratio'), 2)}x"
            " | – |"
        )
    lines += [
        "",
        "## Accuracy against the reference model",
        "",
        "Map drift in pixels of the 288 grid; MS-SSIM-M and LD-M of this model's "
        "rectifications against the reference model's (LD via OpenCV DIS flow, not "
        "SIFT-flow: absolute values differ from the paper's).",
        "",
        "| model | kind | drift mean px | drift max px | MS-SSIM-M | LD-M |",
        "|---|---|---|---|---|---|",
    ]
    for m in report["models"]:
        for kind in KINDS:
            row = m["accuracy"].get(kind, {})
            if "drift_mean_px" in row:
                lines.append(
                    f"| {m['name']} | {kind} | {_fmt(row['drift_mean_px'])} | "
                    f"{_fmt(row['drift_max_px'])} | {_fmt(row['ms_ssim_m_vs_ref'])} | "
                    f"{_fmt(row['ld_m_vs_ref'], 2)} |"
                )
    lines += [
        "",
        "## Accuracy against ground truth (generated crops)",
        "",
        "| model | kind | map error px | MS-SSIM-M vs GT rectification |",
        "|---|---|---|---|",
    ]
    for m in report["models"]:
        for kind in KINDS[:3]:
            row = m["accuracy"].get(kind, {})
            if "gt_map_error_px" in row:
                lines.append(
                    f"| {m['name']} | {kind} | {_fmt(row['gt_map_error_px'], 2)} | "
                    f"{_fmt(row['gt_ms_ssim_m'])} |"
                )
    if report.get("targets"):
        lines += [
            "",
            "## int8 targets",
            "",
            "| model | check | value | target | met |",
            "|---|---|---|---|---|",
        ]
        for t in report["targets"]:
            lines.append(
                f"| {t['model']} | {t['check']} | {_fmt(t['value'])} | {t['target']} | "
                f"{'yes' if t['met'] else '**no**'} |"
            )
    if report.get("pipeline"):
        from .pipeline import pipeline_markdown

        lines += pipeline_markdown(report["pipeline"])
    return "\n".join(lines) + "\n"


def targets(report: dict) -> list[dict]:
    """The issue's int8 targets, checked for every int8 model."""
    checks = []
    for m in report["models"]:
        if m["precision"] != "int8":
            continue
        acc = m["accuracy"]
        drift_mean = max(
            (acc[k]["drift_mean_px"] for k in acc if "drift_mean_px" in acc[k]), default=None
        )
        drift_max = max(
            (acc[k]["drift_max_px"] for k in acc if "drift_max_px" in acc[k]), default=None
        )
        for check, value, target, met in [
            (
                "latency vs fp32 (2 threads)",
                m.get("latency_ratio"),
                "≤ 0.5x",
                m.get("latency_ratio") is not None and m["latency_ratio"] <= 0.5,
            ),
            (
                "worst per-kind mean drift px",
                drift_mean,
                "≤ 0.5",
                drift_mean is not None and drift_mean <= 0.5,
            ),
            ("max drift px", drift_max, "≤ 3", drift_max is not None and drift_max <= 3),
            ("file MB", m["file_mb"], "≤ 30", m["file_mb"] <= 30),
        ]:
            checks.append(
                {
                    "model": m["name"],
                    "check": check,
                    "value": value,
                    "target": target,
                    "met": bool(met),
                }
            )
    return checks


def plots(report: dict, out: Path) -> list[str]:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return []
    written = []
    names = [m["name"] for m in report["models"]]
    fig, ax = plt.subplots(figsize=(max(5, 1.6 * len(names)), 3.6))
    for offset, threads in ((-0.2, "1"), (0.2, "2")):
        values = [m["latency"].get(threads, {}).get("median_ms", 0) for m in report["models"]]
        ax.bar(
            [i + offset for i in range(len(names))],
            values,
            width=0.4,
            label=f"{threads} thread{'s' if threads != '1' else ''}",
        )
    ax.set_xticks(range(len(names)), names, rotation=15, fontsize=8)
    ax.set_ylabel("median latency (ms)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "latency.png", dpi=110)
    plt.close(fig)
    written.append("latency.png")

    fig, ax = plt.subplots(figsize=(5, 3.6))
    for m in report["models"]:
        acc = [v["drift_mean_px"] for v in m["accuracy"].values() if "drift_mean_px" in v]
        two = m["latency"].get("2")
        if acc and two:
            ax.scatter(two["median_ms"], max(acc))
            ax.annotate(m["name"], (two["median_ms"], max(acc)), fontsize=7)
    ax.set_xlabel("median latency, 2 threads (ms)")
    ax.set_ylabel("worst per-kind mean drift (px)")
    fig.tight_layout()
    fig.savefig(out / "drift_vs_latency.png", dpi=110)
    plt.close(fig)
    written.append("drift_vs_latency.png")
    return written


def write_report(report: dict, out: Path) -> list[str]:
    out.mkdir(parents=True, exist_ok=True)
    report["targets"] = targets(report)
    write_bytes_atomically(out / "report.json", json.dumps(report, indent=1).encode())
    write_bytes_atomically(out / "report.md", markdown(report).encode())
    return ["report.json", "report.md", *plots(report, out)]
