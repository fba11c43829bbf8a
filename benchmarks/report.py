"""Writing the benchmark record as report.json, report.md and PNG plots."""

from __future__ import annotations

import json
from pathlib import Path

from doctrpp.export.tolerances import INT8_DRIFT_TARGET_PX
from doctrpp.files import write_bytes_atomically

from .cross_shot import UNTOUCHED
from .report_sections import REAL_KINDS, fmt, kind_rows, markdown_sections_for_peers

GENERATED_KINDS = ("complete", "partial", "none")
KINDS = (*GENERATED_KINDS, *REAL_KINDS)
INT8_LATENCY_TARGET = 0.67  # x ONNX fp32 at 2 threads; and not slower at 1 thread
NOISY_SPREAD = 1.25  # p90 / median above this: timings are noisy


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
        *[f"- **warning**: {w}" for w in noise_warnings(report)],
        "",
        "## Recommendations",
        "",
        *[f"- {line}" for line in recommendations(report)],
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
            f"{fmt(one and one['median_ms'], 0)} / {fmt(one and one['p90_ms'], 0)} | "
            f"{fmt(one and one['fps'], 2)} | {fmt(two and two['median_ms'], 0)} / "
            f"{fmt(two and two['p90_ms'], 0)} | {fmt(two and two['fps'], 2)} | "
            f"{fmt(m.get('latency_ratio'), 2)}x | {fmt(m.get('peak_rss_mb'), 0)} |"
        )
    for extra in report.get("extra_rows", []):
        lines.append(
            f"| {extra['name']} | {extra['format']} | {extra['precision']} | – | – | – | "
            f"{fmt(extra['median_ms'], 0)} / {fmt(extra['p90_ms'], 0)} | "
            f"{fmt(1000 / extra['median_ms'], 2)} | {fmt(extra.get('latency_ratio'), 2)}x"
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
    lines += kind_rows(
        report["models"],
        KINDS,
        "drift_mean_px",
        lambda row: [
            fmt(row["drift_mean_px"]),
            fmt(row["drift_max_px"]),
            fmt(row["ms_ssim_m_vs_ref"]),
            fmt(row["ld_m_vs_ref"], 2),
        ],
    )
    lines += [
        "",
        "## Accuracy against ground truth (generated crops)",
        "",
        "| model | kind | map error px | MS-SSIM-M vs GT rectification |",
        "|---|---|---|---|",
    ]
    for kind, row in sorted(report.get("untouched", {}).items()):
        lines.append(
            f"| untouched input | {kind} | {fmt(row['gt_map_error_px'], 2)} | "
            f"{fmt(row['gt_ms_ssim_m'])} |"
        )
    lines += kind_rows(
        [*report["models"], *report.get("peers", [])],
        GENERATED_KINDS,
        "gt_map_error_px",
        lambda row: [fmt(row["gt_map_error_px"], 2), fmt(row["gt_ms_ssim_m"])],
    )
    lines += markdown_sections_for_peers(report)
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
                f"| {t['model']} | {t['check']} | {fmt(t['value'])} | {t['target']} | "
                f"{'yes' if t['met'] else '**no**'} |"
            )
    if report.get("pipeline"):
        from .pipeline import pipeline_markdown

        lines += pipeline_markdown(report["pipeline"])
    return "\n".join(lines) + "\n"


def _worst(model: dict, kinds: tuple[str, ...], metric: str) -> float | None:
    values = [model["accuracy"][k][metric] for k in kinds if metric in model["accuracy"].get(k, {})]
    return max(values) if values else None


def meets_drift(model: dict) -> bool:
    """Drift within the int8 target on generated and on real-photo crops (if measured)."""
    for kinds in (GENERATED_KINDS, REAL_KINDS):
        mean, top = _worst(model, kinds, "drift_mean_px"), _worst(model, kinds, "drift_max_px")
        if mean is not None and mean > INT8_DRIFT_TARGET_PX["mean"]:
            return False
        if top is not None and top > INT8_DRIFT_TARGET_PX["max"]:
            return False
    return True


def targets(report: dict) -> list[dict]:
    """The int8 targets, checked for every int8 model: drift on generated and on real-photo
    crops, latency against ONNX fp32 at 2 threads and at 1 thread."""
    checks = []
    mean_target, max_target = INT8_DRIFT_TARGET_PX["mean"], INT8_DRIFT_TARGET_PX["max"]
    for m in report["models"]:
        if m["precision"] != "int8":
            continue
        ratios = m.get("latency_ratio_by_threads", {})
        rows = []
        for label, kinds in (("generated", GENERATED_KINDS), ("real-photo", REAL_KINDS)):
            mean, top = _worst(m, kinds, "drift_mean_px"), _worst(m, kinds, "drift_max_px")
            if mean is None:
                continue
            rows.append(
                (
                    f"worst per-kind mean drift px ({label} crops)",
                    mean,
                    f"≤ {mean_target:g}",
                    mean <= mean_target,
                )
            )
            rows.append(
                (f"max drift px ({label} crops)", top, f"≤ {max_target:g}", top <= max_target)
            )
        if "2" in ratios:
            rows.append(
                (
                    "latency vs reference, 2 threads",
                    ratios["2"],
                    f"≤ {INT8_LATENCY_TARGET}x",
                    ratios["2"] <= INT8_LATENCY_TARGET,
                )
            )
        if "1" in ratios:
            rows.append(
                (
                    "latency vs reference, 1 thread",
                    ratios["1"],
                    "≤ 1.0x (not slower)",
                    ratios["1"] <= 1.0,
                )
            )
        rows.append(("file MB", m["file_mb"], "≤ 30", m["file_mb"] <= 30))
        for check, value, target, met in rows:
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


def noise_warnings(report: dict) -> list[str]:
    warnings = []
    for m in report["models"]:
        for threads, t in m["latency"].items():
            spread = t["p90_ms"] / t["median_ms"] if t["median_ms"] > 0 else 0.0
            if spread > NOISY_SPREAD:
                warnings.append(
                    f"{m['name']} at {threads} thread(s): p90 is {spread:.2f}x the median; "
                    "timings are noisy"
                )
    load, cores = report.get("load_average"), report["environment"].get("cores") or 1
    if load is not None and load > 0.5 * cores:
        warnings.append(
            f"load average {load:.1f} on {cores} cores when the benchmark started: other work "
            "was running, timings are slower and noisier than on an idle machine"
        )
    return warnings


def _fastest(models: list[dict], threads: str) -> dict | None:
    timed = [m for m in models if threads in m["latency"]]
    return min(timed, key=lambda m: m["latency"][threads]["median_ms"], default=None)


def recommendations(report: dict) -> list[str]:
    """One line per target: the fastest file that keeps the int8 drift target."""
    faithful = [m for m in report["models"] if m["precision"] != "int8" or meets_drift(m)]
    lines, recommended = [], set()
    for target, formats, threads in (
        ("phone", ("tflite",), "2"),
        ("CPU server", ("onnx", "tflite"), "2"),
    ):
        best = _fastest([m for m in faithful if m["format"] in formats], threads)
        if best is None:
            lines.append(f"{target}: no benchmarked {'/'.join(formats)} file keeps the targets")
            continue
        t = best["latency"][threads]
        one = best["latency"].get("1")
        recommended.add(best["name"])
        lines.append(
            f"{target}: **{best['name']}** ({best['precision']}, {best['file_mb']:.1f} MB): "
            f"{t['median_ms']:.0f} ms at {threads} threads"
            + (f", {one['median_ms']:.0f} ms at 1 thread" if one else "")
            + f", {best.get('latency_ratio', 1):.2f}x the reference"
            + (
                " (the fastest faithful file, though over the int8 speed target)"
                if _int8_too_slow(best)
                else ""
            )
        )
    rejected = [
        m["name"] for m in report["models"] if m["precision"] == "int8" and not meets_drift(m)
    ]
    if rejected:
        lines.append(f"not recommended (drift over target): {', '.join(rejected)}")
    not_faster = [
        f"{m['name']} ({m['latency_ratio']:.2f}x)"
        for m in report["models"]
        if _int8_too_slow(m) and m["name"] not in recommended
    ]
    if not_faster:
        lines.append(
            "faithful but not fast enough to pay for int8 (over "
            f"{INT8_LATENCY_TARGET}x the reference at 2 threads): {', '.join(not_faster)}"
        )
    return lines


def _int8_too_slow(model: dict) -> bool:
    """A faithful int8 file over the speed target (2 threads, x the reference)."""
    return (
        model["precision"] == "int8"
        and meets_drift(model)
        and model.get("latency_ratio", 0) > INT8_LATENCY_TARGET
    )


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

    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for m in report["models"]:
        acc = [v["drift_mean_px"] for v in m["accuracy"].values() if "drift_mean_px" in v]
        two = m["latency"].get("2")
        if acc and two:  # a legend, not labels on points: files of equal speed overlap
            ax.scatter(two["median_ms"], max(acc), label=m["name"])
    ax.set_xlabel("median latency, 2 threads (ms)")
    ax.set_ylabel("worst per-kind mean drift (px)")
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    fig.tight_layout()
    fig.savefig(out / "drift_vs_latency.png", dpi=110, bbox_inches="tight")  # keep the legend
    plt.close(fig)
    written.append("drift_vs_latency.png")
    if report.get("cross_shot"):
        cross_shot_plot(report, out, plt)
        written.append("cross_shot_vs_latency.png")
    return written


def cross_shot_plot(report: dict, out: Path, plt) -> None:
    """Each model file's cross-shot MS-SSIM against its latency; the untouched photos and
    the peer as horizontal lines for scale."""
    latency = {m["name"]: m["latency"].get("2", {}).get("median_ms") for m in report["models"]}
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for row in report["cross_shot"]["rows"]:
        # files sit within a few thousandths of each other: a legend, not labels on points
        if latency.get(row["name"]) is not None:
            ax.scatter(latency[row["name"]], row["cross_shot_ms_ssim"], label=row["name"])
        elif row["name"] not in latency:  # the untouched photos, a peer
            untouched = row["name"] == UNTOUCHED
            style = {"linestyle": "--" if untouched else ":", "linewidth": 1.0}
            colour = "gray" if untouched else "black"
            ax.axhline(row["cross_shot_ms_ssim"], label=row["name"], color=colour, **style)
    ax.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.02, 0.5))
    ax.set_xlabel("median latency, 2 threads (ms)")
    ax.set_ylabel("cross-shot MS-SSIM (real photos)")
    fig.tight_layout()
    fig.savefig(out / "cross_shot_vs_latency.png", dpi=110, bbox_inches="tight")
    plt.close(fig)


def write_report(report: dict, out: Path) -> list[str]:
    out.mkdir(parents=True, exist_ok=True)
    report["targets"] = targets(report)
    write_bytes_atomically(out / "report.json", json.dumps(report, indent=1).encode())
    write_bytes_atomically(out / "report.md", markdown(report).encode())
    return ["report.json", "report.md", *plots(report, out)]
