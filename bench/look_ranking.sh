#!/usr/bin/env bash
# bench/look_ranking.sh — the pictures of issue 15's blind ranking (bench/look_ranking/README.md).
#
#   bench/look_ranking.sh                 # renders bench/look_ranking/new (the five TOML examples with ./build/iqc)
#                                         # and bench/look_ranking/hand (bench/handwritten/*.frag), 480x270
#   BLIND=/tmp/blind SEED=7 bench/look_ranking.sh
#                                         # also a shuffled copy for a reviewer: BLIND/set1..5/{A,B,C}.png, with
#                                         # the key in BLIND.key (outside the folder the reviewer is shown)
#
# bench/look_ranking/old holds the pictures of the build before the look's last round of work (5754a4a);
# they are kept as they were, not re-rendered.
set -euo pipefail
cd "$(dirname "$0")/.."
IQC="${IQC:-./build/iqc}"
SIZE="${SIZE:-480x270}"
SCENES=(christmas_tree gallery glass_and_mirror lights_and_effects menger)
mkdir -p bench/look_ranking/new bench/look_ranking/hand
for s in "${SCENES[@]}"; do
  "$IQC" render "examples/$s.iq" -o "bench/look_ranking/new/$s.png" --size "$SIZE" -q
  "$IQC" render "bench/handwritten/$s.frag" -o "bench/look_ranking/hand/$s.png" --size "$SIZE" -q
done
echo "look_ranking: rendered ${#SCENES[@]} scenes into bench/look_ranking/new and hand ($SIZE)"
if [ -n "${BLIND:-}" ]; then
  python3 - "$BLIND" "${SEED:-1}" "${SCENES[@]}" <<'PY'
import os, random, shutil, sys
out, seed, scenes = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
random.seed(seed)
random.shuffle(scenes)
key = []
for i, s in enumerate(scenes, 1):
    srcs = ["new", "hand", "old"]
    random.shuffle(srcs)
    d = os.path.join(out, f"set{i}")
    os.makedirs(d, exist_ok=True)
    for letter, src in zip("ABC", srcs):
        shutil.copy(f"bench/look_ranking/{src}/{s}.png", os.path.join(d, f"{letter}.png"))
    key.append(f"set{i} ({s}): " + ", ".join(f"{l}={src}" for l, src in zip("ABC", srcs)))
with open(out.rstrip("/") + ".key", "w") as f:
    f.write("\n".join(key) + "\n")
print(f"look_ranking: blind set in {out}, key in {out.rstrip('/')}.key")
PY
fi
