#!/usr/bin/env bash
# `make demo`: registers a synthetic street pair (quadrix synth) with quadrix register and prints
# the estimate beside the ground truth. Usage: bash experiments/command_line/demo.sh BUILD_DIR [OUT_DIR]
# Falls back to the paper's real KITTI demo pair (../shared/data, frame 000000 -> 004438) when the
# build has no `synth` command.
set -euo pipefail
build_dir="${1:?usage: bash experiments/command_line/demo.sh BUILD_DIR [OUT_DIR]}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
quadrix="$build_dir/bin/quadrix"
[[ -x "$quadrix" ]] || { echo "demo: $quadrix not found; build the 'quadrix' target first" >&2; exit 2; }
out="${2:-$build_dir/demo}"
mkdir -p "$out"

print_truth() {  # prints a 4x4 ground-truth file with a caption
  echo "ground truth (maps source into the target frame):"
  awk '{ printf "%12.6f %12.6f %12.6f %12.6f\n", $1, $2, $3, $4 }' "$1"
}

if "$quadrix" synth --help >/dev/null 2>&1; then
  echo "== demo: synthetic street pair scanned by a simulated HDL-64E (quadrix synth street --seed 3) =="
  "$quadrix" synth street --seed 3 --sensor hdl64 --out "$out/street" >/dev/null
  # The first pair of the folder's pairs.tsv: id source target gt ...
  read -r _ source target gt _ < <(sed -n 2p "$out/street/pairs.tsv")
  source="$out/street/$source"; target="$out/street/$target"; gt="$out/street/$gt"
else
  data="$here/../../../shared/data"
  echo "== demo: 'quadrix synth' is not in this build; using the paper's KITTI demo pair (000000 -> 004438) =="
  source="$data/kitti00/velodyne/000000.bin"; target="$data/kitti00/velodyne/004438.ply"
  gt="$data/kitti00/gt/T_004438_from_000000.txt"
  [[ -f "$source" ]] || { echo "demo: $source not found (../shared/data absent)" >&2; exit 2; }
fi
"$quadrix" register "$source" "$target" --gt "$gt" --out "$out/register"
print_truth "$gt"
echo "pictures: $out/register/bev.png (bird's-eye view), $out/register/merged.ply (target grey, source orange), $out/register/view.html (interactive 3-D page)"
