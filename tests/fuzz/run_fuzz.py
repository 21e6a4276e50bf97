#!/usr/bin/env python3
"""Runs every libFuzzer harness of a QUADRIX_FUZZ build one after the other (`make fuzz` calls it)
and writes a summary table to BUILD/fuzz-summary.md and stdout.

Each harness fuzzes for --seconds (and at most --runs executions when given) with a writable
corpus BUILD/corpus/<harness>, read-only seeds/<harness>, regressions/<harness> and the cut-outs of
the shared data (shared_data_seeds.py, written to BUILD/shared-seeds when --data exists). Limits:
-timeout=10 (a slower input is a hang), -rss_limit_mb=2048 and -malloc_limit_mb=2048 (a reader
that allocates from a header count before checking the file size shows up as out-of-memory).
Crash, leak, timeout and out-of-memory reproducers are written to BUILD/artifacts/<harness>/.
Exits 1 when any harness failed, naming its reproducer and its log (BUILD/logs/<harness>.log).

    python3 tests/fuzz/run_fuzz.py --build build-fuzz --seconds 60 [--runs N] [--only pcd,npy]
"""

import argparse
import os
import pathlib
import re
import subprocess
import sys
import time

HERE = pathlib.Path(__file__).resolve().parent

# Harness -> libFuzzer dictionary under dictionaries/ (harnesses without one mutate bytes only).
DICTIONARIES = {
    "ply_cloud": "ply.dict",
    "ply_mesh": "ply.dict",
    "pcd": "pcd.dict",
    "npy": "npy.dict",
    "text_cloud": "text.dict",
    "pose_matrix": "text.dict",
    "kitti_poses": "text.dict",
    "kitti_calibration": "kitti_calibration.dict",
    "scene_model_json": "scene_model_json.dict",
    "registration_config": "registration_config.dict",
    "las": "las.dict",
}

FAILURE_KINDS = [
    ("ERROR: libFuzzer: timeout", "timeout"),
    ("ERROR: LeakSanitizer", "leak"),
    ("ERROR: libFuzzer: out-of-memory", "out-of-memory"),
    ("ERROR: libFuzzer: malloc limit", "out-of-memory"),
    ("ERROR: AddressSanitizer", "crash (ASan)"),
    ("runtime error:", "crash (UBSan)"),
    ("ERROR: libFuzzer: deadly signal", "crash"),
]


def parse_log(text):
    """Executions, exec/s, cov, ft, corpus size and the failure kind from a libFuzzer log."""
    result = {"executions": None, "exec_per_second": None, "cov": None, "ft": None, "corpus": None, "kind": None}
    match = re.search(r"stat::number_of_executed_units:\s*(\d+)", text)
    if match:
        result["executions"] = int(match.group(1))
    match = re.search(r"stat::average_exec_per_sec:\s*(\d+)", text)
    if match:
        result["exec_per_second"] = int(match.group(1))
    coverage_lines = [line for line in text.splitlines() if " cov: " in line]
    if coverage_lines:
        last = coverage_lines[-1]
        for key, pattern in (("cov", r" cov: (\d+)"), ("ft", r" ft: (\d+)"), ("corpus", r" corp: (\d+)")):
            match = re.search(pattern, last)
            if match:
                result[key] = int(match.group(1))
    for marker, kind in FAILURE_KINDS:
        if marker in text:
            result["kind"] = kind
            break
    return result


def run_harness(build, name, seconds, runs, shared_seeds):
    """Runs bin/fuzz_<name> once with the limits of the module docstring; its parsed log and outcome."""
    executable = build / "bin" / f"fuzz_{name}"
    corpus = build / "corpus" / name
    artifacts = build / "artifacts" / name
    log_path = build / "logs" / f"{name}.log"
    for folder in (corpus, artifacts, log_path.parent):
        folder.mkdir(parents=True, exist_ok=True)
    command = [str(executable), f"-max_total_time={seconds}", "-timeout=10", "-rss_limit_mb=2048",
               "-malloc_limit_mb=2048", "-print_final_stats=1", f"-artifact_prefix={artifacts}/"]
    if runs:
        command.append(f"-runs={runs}")
    if name in DICTIONARIES:
        command.append(f"-dict={HERE / 'dictionaries' / DICTIONARIES[name]}")
    command.append(str(corpus))
    for folder in (HERE / "seeds" / name, HERE / "regressions" / name, shared_seeds / name):
        if folder.is_dir():
            command.append(str(folder))
    environment = dict(os.environ)
    environment.setdefault("UBSAN_OPTIONS", "print_stacktrace=1")
    started = time.monotonic()
    with open(log_path, "w") as log:
        log.write(" ".join(command) + "\n")
        log.flush()
        process = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, env=environment)
    elapsed = time.monotonic() - started
    text = log_path.read_text(errors="replace")
    result = parse_log(text)
    result.update(name=name, returncode=process.returncode, seconds=elapsed, log=log_path,
                  reproducers=re.findall(r"Test unit written to (\S+)", text))
    if process.returncode != 0 and result["kind"] is None:
        result["kind"] = f"failed (exit {process.returncode})"
    if process.returncode == 0:
        result["kind"] = None
    return result


def number(value):
    """A count with thousands separators, or '-' when unknown."""
    return "-" if value is None else f"{value:,}"


def summary_table(results, seconds, runs):
    """The Markdown table of fuzz-summary.md: one row per harness."""
    limit = f"{seconds} s" + (f" or {runs:,} executions" if runs else "")
    lines = [f"Fuzzing summary: each harness for {limit}, one after the other.", "",
             "| harness | executions | exec/s | cov | ft | corpus | result |",
             "|---|---:|---:|---:|---:|---:|---|"]
    for r in results:
        outcome = "ok" if r["kind"] is None else r["kind"]
        lines.append(f"| fuzz_{r['name']} | {number(r['executions'])} | {number(r['exec_per_second'])} | "
                     f"{number(r['cov'])} | {number(r['ft'])} | {number(r['corpus'])} | {outcome} |")
    return "\n".join(lines) + "\n"


def main():
    """Cuts the shared-data seeds, runs every harness, writes the summary; 1 when any harness failed."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--build", default="build-fuzz", help="the QUADRIX_FUZZ build folder (bin/fuzz_*)")
    parser.add_argument("--seconds", type=int, default=60, help="fuzzing time of each harness")
    parser.add_argument("--runs", type=int, default=0, help="stop a harness after this many executions (0: no limit)")
    parser.add_argument("--data", default=str(HERE.parents[2] / "shared" / "data"),
                        help="the shared data folder seeds are cut from (skipped when absent)")
    parser.add_argument("--only", default="", help="comma-separated harness names (default: every fuzz_* in BUILD/bin)")
    arguments = parser.parse_args()

    build = pathlib.Path(arguments.build).resolve()
    names = sorted(path.name[len("fuzz_"):] for path in (build / "bin").glob("fuzz_*") if os.access(path, os.X_OK))
    if arguments.only:
        wanted = arguments.only.split(",")
        missing = [name for name in wanted if name not in names]
        if missing:
            sys.exit(f"run_fuzz: no harness {', '.join(missing)} in {build / 'bin'}")
        names = wanted
    if not names:
        sys.exit(f"run_fuzz: no fuzz_* executables in {build / 'bin'}; build the target fuzz_harnesses first")

    shared_seeds = build / "shared-seeds"
    data = pathlib.Path(arguments.data)
    if data.is_dir():
        subprocess.run([sys.executable, str(HERE / "shared_data_seeds.py"), str(data), str(shared_seeds)], check=True)
    else:
        print(f"run_fuzz: {data} absent, fuzzing from seeds/ and regressions/ only")

    results = []
    for name in names:
        print(f"run_fuzz: fuzz_{name} for {arguments.seconds} s ...", flush=True)
        result = run_harness(build, name, arguments.seconds, arguments.runs, shared_seeds)
        results.append(result)
        outcome = "ok" if result["kind"] is None else result["kind"].upper()
        print(f"run_fuzz: fuzz_{name}: {outcome}, {number(result['executions'])} executions, "
              f"cov {number(result['cov'])}, ft {number(result['ft'])} ({result['seconds']:.0f} s)", flush=True)

    table = summary_table(results, arguments.seconds, arguments.runs)
    (build / "fuzz-summary.md").write_text(table)
    print()
    print(table)
    failed = [r for r in results if r["kind"] is not None]
    for r in failed:
        print(f"run_fuzz: fuzz_{r['name']} {r['kind']}: log {r['log']}")
        for reproducer in r["reproducers"]:
            print(f"run_fuzz:   reproducer {reproducer}  (replay: {build / 'bin' / ('fuzz_' + r['name'])} {reproducer})")
    if failed:
        print(f"run_fuzz: {len(failed)} of {len(results)} harnesses failed")
        return 1
    print(f"run_fuzz: all {len(results)} harnesses ran without a crash, leak, timeout or out-of-memory")
    return 0


if __name__ == "__main__":
    sys.exit(main())
