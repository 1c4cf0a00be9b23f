#!/usr/bin/env python3
"""Writes output/evaluation/report.md and its plots from the CSV and JSON files that
scripts/evaluate.sh had the evaluation tools write (evaluate_descriptors, evaluate_pnp,
evaluate_place_recognition,
run_dataset with the keyframe presets, evaluate_relocalization).

usage: evaluation_report.py EVALUATION_DIR
"""
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")  # no display: files only
import matplotlib.pyplot as plt  # noqa: E402

# The thesis' figures (EuRoC machine hall, AGAST/BRISK), quoted beside ours.
THESIS_RELOCALIZATION = {
    "MH01": "pose in 2.8 % of test frames, 64 % of them within 10 cm",
    "MH02": "pose in 2.2 % of test frames, 55 % of them within 10 cm",
    "MH03": "pose in 15.7 % of test frames, 23 % of them within 10 cm",
}
DMAX_VALUES = ["0.1", "0.25", "0.5", "1"]


def read_csv(path):
    with open(path, newline="") as file:
        return list(csv.DictReader(file))


def read_json(path):
    with open(path) as file:
        return json.load(file)


def number(text):
    return float(text) if text not in ("", "null", None) else float("nan")


def save(figure, directory, name):
    path = os.path.join(directory, name)
    figure.tight_layout()
    figure.savefig(path, dpi=90)
    plt.close(figure)
    return name


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def descriptor_section(directory):
    folder = os.path.join(directory, "descriptors")
    if not os.path.isdir(folder):
        return ""
    curves = read_csv(os.path.join(folder, "descriptor_pr.csv"))
    areas = read_csv(os.path.join(folder, "descriptor_auc.csv"))
    text = ["## Descriptors: precision-recall (`evaluate_descriptors`)\n"]
    text.append(
        "Nearest-neighbour matching with the ratio test d1 < t·d2, t swept from 0 to 1; a match "
        "is correct when the reference key point carried into the test image by the known "
        "geometry lies within ε of the matched key point. AUC: area under precision over "
        "recall.\n")
    cases = list(dict.fromkeys(row["case"] for row in areas))
    pairs = list(dict.fromkeys(row["pair"] for row in areas))
    auc = {(row["case"], row["pair"]): row for row in areas}
    rows = []
    for case in cases:
        rows.append([case] + [
            f"{number(auc[(case, pair)]['auc']):.3f}" if (case, pair) in auc else "–"
            for pair in pairs
        ])
    text.append(table(["case (AUC)"] + pairs, rows))
    speed = []
    for pair in pairs:
        times = [number(row["milliseconds_per_image"]) for row in areas if row["pair"] == pair]
        speed.append([pair, f"{sum(times) / len(times):.1f}"])
    text.append("\nTime to detect and describe one image, mean over the cases:\n\n")
    text.append(table(["pair", "ms per image"], speed))
    groups = list(dict.fromkeys(case.split(":")[0] for case in cases))
    mean_rows = []
    for group in groups:
        row = [group]
        for pair in pairs:
            values = [number(r["auc"]) for r in areas
                      if r["pair"] == pair and r["case"].split(":")[0] == group]
            row.append(f"{sum(values) / len(values):.3f}" if values else "–")
        mean_rows.append(row)
    text.append("\nMean AUC per set of cases:\n\n")
    text.append(table(["cases (mean AUC)"] + pairs, mean_rows))
    for group in groups:
        members = [case for case in cases if case.split(":")[0] == group]
        columns = min(3, len(members))
        rows_needed = (len(members) + columns - 1) // columns
        figure, axes = plt.subplots(rows_needed, columns, figsize=(4.5 * columns, 3.8 * rows_needed),
                                    squeeze=False)
        for index, case in enumerate(members):
            axis = axes[index // columns][index % columns]
            for pair in pairs:
                points = [(number(r["recall"]), number(r["precision"])) for r in curves
                          if r["case"] == case and r["pair"] == pair]
                if points:
                    axis.plot([p[0] for p in points], [p[1] for p in points], label=pair)
            axis.set_title(case.split(":", 1)[-1], fontsize="medium")
            axis.set_xlabel("recall")
            axis.set_ylabel("precision")
            axis.set_xlim(0, 1)
            axis.set_ylim(0, 1.02)
            axis.grid(True, alpha=0.3)
        for index in range(len(members), rows_needed * columns):
            axes[index // columns][index % columns].axis("off")
        axes[0][0].legend(fontsize="x-small")
        figure.suptitle(f"Descriptor precision-recall: {group} (ratio test swept)")
        name = save(figure, directory, f"descriptors_{group}.png")
        text.append(f"\n![Descriptor precision-recall, {group}]({name})\n")
    return "\n".join(text)


def pnp_section(directory):
    folder = os.path.join(directory, "pnp")
    if not os.path.isdir(folder):
        return ""
    summary = read_csv(os.path.join(folder, "pnp_summary.csv"))
    bins = read_csv(os.path.join(folder, "pnp.csv"))
    text = ["## PnP kernels (`evaluate_pnp`)\n"]
    text.append(
        "Stereo 3-D points of a reference frame, descriptor matches in later frames, every "
        "kernel inside the same RANSAC, with and without the refinement; errors against the "
        "ground-truth relative pose.\n")
    for sequence in dict.fromkeys(row["sequence"] for row in summary):
        rows = []
        for row in summary:
            if row["sequence"] != sequence:
                continue
            trials = int(row["trials"])
            rows.append([
                row["kernel"], "yes" if row["refined"] in ("1", "true", "yes") else "no",
                f"{100 * int(row['successes']) / trials:.1f} %" if trials else "–",
                f"{100 * number(row['translation_error_mean_m']):.2f} ± "
                f"{100 * number(row['translation_error_std_m']):.2f}",
                f"{number(row['rotation_error_mean_deg']):.3f} ± "
                f"{number(row['rotation_error_std_deg']):.3f}",
                f"{number(row['time_mean_ms']):.2f} ± {number(row['time_std_ms']):.2f}",
            ])
        text.append(f"\n### {os.path.basename(sequence)}\n\n")
        text.append(table(["kernel", "refined", "success", "translation error [cm]",
                           "rotation error [deg]", "time [ms]"], rows))
        figure, axes = plt.subplots(1, 2, figsize=(12, 4), squeeze=False)
        for column, refined in enumerate(["0", "1"]):
            axis = axes[0][column]
            for kernel in dict.fromkeys(row["kernel"] for row in bins):
                points = sorted((number(r["distance_m"]), 100 * number(r["translation_error_mean_m"]))
                                for r in bins
                                if r["sequence"] == sequence and r["kernel"] == kernel and
                                (r["refined"] in ("1", "true", "yes")) == (refined == "1") and
                                int(r["successes"]) > 0)
                if points:
                    axis.plot([p[0] for p in points], [p[1] for p in points], marker="o",
                              label=kernel)
            axis.set_title(("refined" if refined == "1" else "RANSAC only") + ": " +
                           os.path.basename(sequence))
            axis.set_xlabel("distance reference → test frame [m]")
            axis.set_ylabel("translation error, mean [cm]")
            axis.set_yscale("log")
            axis.grid(True, alpha=0.3)
            axis.legend(fontsize="small")
        name = save(figure, directory, f"pnp_{os.path.basename(sequence)}.png")
        text.append(f"\n![PnP error against distance, {os.path.basename(sequence)}]({name})\n")
    return "\n".join(text)


def preset_section(directory):
    path = os.path.join(directory, "presets", "presets.csv")
    if not os.path.exists(path):
        return ""
    rows = read_csv(path)
    text = ["## Keyframe settings (`config/keyframes_*.yaml`)\n"]
    text.append(
        "Each preset on each sequence: `run_dataset` (keyframes, ATE and RPE of the whole run, "
        "tracking time per frame) and `evaluate_relocalization` with the same preset (recall "
        "at τ 0.9, d_max 0.5 m).\n\n")
    body = []
    for row in rows:
        run = read_json(row["run_summary"])
        relocalization = read_json(row["relocalization_summary"])
        body.append([
            row["sequence"], row["preset"], run["keyframes"],
            f"{100 * run.get('ate_rmse', float('nan')):.2f}",
            f"{100 * run.get('rpe_trans_rmse', float('nan')):.3f}",
            f"{run['tracking_total_ms_mean']:.1f}",
            f"{relocalization['recall']:.2f} ({relocalization['relevant_frames']} relevant)",
        ])
    text.append(table(["sequence", "preset", "keyframes", "ATE RMSE [cm]",
                       "RPE [cm/frame]", "tracking [ms/frame]", "relocalization recall"],
                      body))
    return "\n".join(text)


def at_default(row):
    if not row.get("precision_at_default"):
        return "–"
    return (f"{100 * number(row['precision_at_default']):.1f} / "
            f"{100 * number(row['recall_at_default']):.1f} %")


def place_recognition_section(directory):
    folder = os.path.join(directory, "place_recognition")
    if not os.path.isdir(folder):
        return ""
    text = ["## Place recognition: FAB-MAP alone and a tf-idf baseline (`evaluate_place_recognition`)\n"]
    text.append(
        "Every frame in turn queries the earlier frames' places (frames within the exclusion "
        "window excluded); the acceptance threshold is swept (FAB-MAP: the best place's log odds "
        "against a new place; tf-idf: the cosine). Ground truth: two frames show one "
        "place when at least half of one's stereo points land in the other's image. FAB-MAP "
        "with one place per image, and with places updated on revisits; tf-idf cosine over "
        "the same words. Dots: FAB-MAP at its default threshold (fabmap.match_log_odds).\n\n")
    rows = []
    labels = sorted(os.listdir(folder))
    figure, axes = plt.subplots(1, len(labels), figsize=(4.5 * len(labels), 4), squeeze=False)
    for index, label in enumerate(labels):
        summary = read_csv(os.path.join(folder, label, "place_recognition_summary.csv"))
        curves = read_csv(os.path.join(folder, label, "place_recognition_pr.csv"))
        for row in summary:
            rows.append([label, row["method"], row["mode"], row["queries_with_true_match"],
                         f"{100 * number(row['recall_at_100_precision']):.1f} %",
                         f"{number(row['auc']):.3f}", row.get("declared_new_places", "–"),
                         at_default(row)])
        axis = axes[0][index]
        for row in summary:
            points = [(number(r["recall"]), number(r["precision"])) for r in curves
                      if r["method"] == row["method"] and r["mode"] == row["mode"]]
            line, = axis.plot([p[0] for p in points], [p[1] for p in points],
                              label=f"{row['method']} ({row['mode']})")
            if row.get("precision_at_default"):
                axis.plot([number(row["recall_at_default"])], [number(row["precision_at_default"])],
                          "o", color=line.get_color())
        axis.set_title(f"Place recognition: {label}")
        axis.set_xlabel("recall")
        axis.set_ylabel("precision")
        axis.set_xlim(0, 1)
        axis.set_ylim(0, 1.02)
        axis.grid(True, alpha=0.3)
        axis.legend(fontsize="x-small")
    text.append(table(["sequence", "method", "places", "queries with a true match",
                       "recall at 100 % precision", "AUC", "new places declared",
                       "precision / recall at the default threshold"], rows))
    name = save(figure, directory, "place_recognition_pr.png")
    text.append(f"\n![Place recognition precision-recall]({name})\n")
    return "\n".join(text)


def relocalization_plots(folder, directory, label):
    frames = read_csv(os.path.join(folder, "frames.csv"))
    recall = read_csv(os.path.join(folder, "recall.csv"))
    names = []
    figure, axes = plt.subplots(1, 2, figsize=(12, 4))
    for dmax in DMAX_VALUES:
        points = [(number(r["tau"]), number(r["recall"])) for r in recall
                  if abs(number(r["dmax_m"]) - float(dmax)) < 1e-9]
        axes[0].plot([p[0] for p in points], [p[1] for p in points], marker=".",
                     label=f"d_max {dmax} m")
    axes[0].set_title(f"Relocalization recall: {label}")
    axes[0].set_xlabel("relevance threshold τ (share of keyframe points in view)")
    axes[0].set_ylabel("recall")
    axes[0].set_ylim(0, 1.02)
    axes[0].grid(True, alpha=0.3)
    axes[0].legend(fontsize="small")
    estimated = [r for r in frames if r["estimated"] == "1" and r["error_m"] != ""]
    axes[1].scatter([number(r["estimated_distance_m"]) for r in estimated],
                    [100 * number(r["error_m"]) for r in estimated], s=8)
    axes[1].set_title(f"Relocalization error: {label}")
    axes[1].set_xlabel("estimated distance keyframe → frame [m]")
    axes[1].set_ylabel("error [cm]")
    axes[1].grid(True, alpha=0.3)
    names.append(save(figure, directory, f"relocalization_{label}.png"))

    figure = plt.figure(figsize=(7, 6))
    axis = figure.add_subplot(projection="3d")
    for mapping, colour, name in (("1", "tab:blue", "mapping on"), ("0", "tab:orange",
                                                                     "mapping off (test)")):
        points = [r for r in frames if r["mapping"] == mapping and r["x"] != ""]
        axis.scatter([number(r["x"]) for r in points], [number(r["y"]) for r in points],
                     [number(r["z"]) for r in points], s=3, color=colour, label=name)
    for r in estimated:
        axis.plot([number(r["x"]), number(r["keyframe_x"])],
                  [number(r["y"]), number(r["keyframe_y"])],
                  [number(r["z"]), number(r["keyframe_z"])], color="tab:green", linewidth=0.6)
    axis.plot([], [], color="tab:green", label="relocalized → keyframe")
    axis.set_title(f"Ground-truth path: {label}")
    axis.set_xlabel("x [m]")
    axis.set_ylabel("y [m]")
    axis.set_zlabel("z [m]")
    axis.legend(fontsize="small")
    names.append(save(figure, directory, f"relocalization_{label}_path.png"))
    return names


def relocalization_section(directory):
    folder = os.path.join(directory, "relocalization")
    if not os.path.isdir(folder):
        return ""
    text = ["## Relocalization recall (`evaluate_relocalization`), the thesis' measure\n"]
    text.append(
        "Mapping on the first part of each sequence, then every later frame relocalized against "
        "that map with mapping off. A test frame is relevant at τ when at least the share τ of "
        "some keyframe's 3-D points, carried into it by ground truth, land in its image; the "
        "error is the distance between estimated and true translation keyframe → frame.\n\n")
    rows, pictures = [], []
    for label in sorted(os.listdir(folder)):
        summary_path = os.path.join(folder, label, "summary.json")
        if not os.path.exists(summary_path):
            continue
        s = read_json(summary_path)
        thesis = next((v for k, v in THESIS_RELOCALIZATION.items() if label.startswith(k)), "")
        estimated_share = s["estimated_frames"] / s["test_frames"] if s["test_frames"] else 0
        failures = ", ".join(f"{count} {outcome}" for outcome, count in
                             sorted(s.get("outcomes", {}).items()) if outcome != "success")
        rows.append([
            label, s["map_keyframes"], s["test_frames"], s["relevant_frames"],
            f"{100 * estimated_share:.1f} %", f"{s['recall']:.2f}",
            f"{100 * s['error_below_10cm_fraction']:.0f} %",
            f"{100 * s['error_median_m']:.1f}" if s["error_median_m"] is not None else "–",
            s["wrong_estimates"], failures or "–", thesis
        ])
        pictures += relocalization_plots(os.path.join(folder, label), directory, label)
    text.append(table(["sequence", "map keyframes", "test frames", "relevant (τ 0.9)",
                       "with a pose", "recall (τ 0.9, 0.5 m)", "estimates < 10 cm",
                       "median error [cm]", "wrong (> 0.5 m)", "attempts without a pose",
                       "thesis"], rows))
    text += [f"\n![{name}]({name})\n" for name in pictures]
    return "\n".join(text)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    directory = sys.argv[1]
    parts = ["# Evaluation report\n"]
    info = os.path.join(directory, "machine.txt")
    if os.path.exists(info):
        with open(info) as file:
            parts.append("```\n" + file.read().strip() + "\n```\n")
    for section in (descriptor_section, pnp_section, preset_section, place_recognition_section,
                    relocalization_section):
        part = section(directory)
        if part:
            parts.append(part)
    text = "\n".join(parts)
    while "\n\n\n" in text:  # the sections' pieces each end a paragraph; one blank line
        text = text.replace("\n\n\n", "\n\n")
    with open(os.path.join(directory, "report.md"), "w") as file:
        file.write(text)
    print(f"wrote {os.path.join(directory, 'report.md')}")


if __name__ == "__main__":
    main()
