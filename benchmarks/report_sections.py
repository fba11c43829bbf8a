"""The report's Markdown sections on real photos (reference-free crops, cross-shot
agreement) and on peer models."""

from __future__ import annotations

from pathlib import Path

REAL_KINDS = ("real complete", "real partial", "real none")


def fmt(value, digits: int = 3) -> str:
    if value is None:
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


def kind_rows(models: list[dict], kinds: tuple[str, ...], measured: str, cells) -> list[str]:
    """A table row per model and kind where the model's accuracy for that kind holds
    `measured`: model, kind, then `cells(row)` (formatted values)."""
    lines = []
    for m in models:
        for kind in kinds:
            row = m["accuracy"].get(kind, {})
            if measured in row:
                lines.append(f"| {m['name']} | {kind} | " + " | ".join(cells(row)) + " |")
    return lines


def markdown_sections_for_peers(report: dict) -> list[str]:
    """The reference-free table (models and peers), cross-shot agreement and the peers'
    latency table."""
    return reference_free_markdown(report) + cross_shot_markdown(report) + peers_markdown(report)


def _mean_and_error(pair: list[float] | None, digits: int) -> str:
    return "–" if pair is None else f"{pair[0]:+.{digits}f} ± {pair[1]:.{digits}f}"


def cross_shot_markdown(report: dict) -> list[str]:
    """Both shots of each document rectified and compared with each other
    (`benchmarks.cross_shot`)."""
    section = report.get("cross_shot")
    if not section:
        return []
    reference = next(
        (r.get("paired_against") for r in section["rows"] if "paired_against" in r), ""
    )
    lines = [
        "",
        "## Real photos: cross-shot agreement",
        "",
        f"Both shots of {section['documents']} documents (`<document>_1`, `<document>_2` in "
        f"{Path(section['photos']).name}/), each rectified as `doctrpp rectify` runs the model "
        "(flip-averaged, text lines aligned), then compared with each other by the measures "
        "of a flat-scan benchmark, the other shot standing in for the scan: unmasked "
        "MS-SSIM (higher = the two results agree more) and local distortion (px, lower = "
        "better). An error both shots share counts as agreement. Paired: the mean "
        f"per-document difference from {reference} ± its standard error.",
        "",
        "| entry | MS-SSIM | local distortion px | MS-SSIM, paired | local distortion, paired |",
        "|---|---|---|---|---|",
    ]
    for row in section["rows"]:
        lines.append(
            f"| {row['name']} | {fmt(row['cross_shot_ms_ssim'])} | "
            f"{fmt(row['cross_shot_local_distortion'], 1)} | "
            f"{_mean_and_error(row.get('paired_ms_ssim'), 4)} | "
            f"{_mean_and_error(row.get('paired_local_distortion'), 2)} |"
        )
    return lines


def reference_free_markdown(report: dict) -> list[str]:
    """Real-photo crops have no flat scan: straightness of text lines against the untouched
    crop's (ratio > 1 = straighter), black share and kept share of the output."""
    rows = [m for m in [*report["models"], *report.get("peers", [])] if _has_real(m)]
    if not rows:
        return []
    lines = [
        "",
        "## Real-photo crops (reference-free)",
        "",
        "Text-line coherence (lines aligned across the full width; sees curls) and "
        "straightness (local tilt) of the result / of the untouched crop (1 = unchanged, "
        "higher = better; blind to content cut away and to stretching along lines), "
        "share of the output sampled from outside the photo (black) and share of the photo "
        "kept; bending: the map's mean non-projective part in px of its 288 grid (what it "
        "does beyond a perspective; curled pages need some). The untouched crop scores "
        "1 / 1 / 0 / 1 / 0.",
        "",
        "| model | kind | coherence ratio | straightness ratio | black share | kept share "
        "| bending px |",
        "|---|---|---|---|---|---|---|",
    ]
    return lines + kind_rows(
        rows,
        REAL_KINDS,
        "straightness_ratio",
        lambda row: [
            fmt(row.get("coherence_ratio")),
            fmt(row["straightness_ratio"]),
            fmt(row["black_share"]),
            fmt(row["kept_share"]),
            fmt(row.get("nonprojective_px")),
        ],
    )


def _has_real(model: dict) -> bool:
    return any("straightness_ratio" in model["accuracy"].get(k, {}) for k in REAL_KINDS)


def peers_markdown(report: dict) -> list[str]:
    if not report.get("peers"):
        return []
    lines = [
        "",
        "## Peers (for scale)",
        "",
        "Other published models on the same crops (accuracy rows above); latency timed run "
        "by run against our reference model in the same rounds.",
        "",
        "| peer | format | precision | input | MB | threads | median / p90 ms | vs our reference |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for peer in report["peers"]:
        for threads, t in sorted(peer["latency"].items()):
            lines.append(
                f"| {peer['name']} | {peer['format']} | {peer['precision']} | "
                f"{peer['input']} | {peer['file_mb']:.1f} | {threads} | "
                f"{fmt(t['median_ms'], 0)} / {fmt(t['p90_ms'], 0)} | "
                f"{fmt(t['latency_ratio'], 2)}x |"
            )
    return lines
