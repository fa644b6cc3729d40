#!/bin/bash
# The farm ctest group: a local one-node Slurm cluster renders a 6-frame animation through
# tools/farm/submit-slurm (chunks of 2), and one frame as 3 tiles; every file must equal a local
# render byte for byte. A task that fails once is requeued and the result still complete. The
# cluster is stopped on every exit. Exit 77 (ctest SKIP_RETURN_CODE) only when Slurm is not installed.
#   farm_test.sh VKRAY SOURCE_DIR
set -euo pipefail
vkray="$1"
src="$2"
export PATH="$PATH:/usr/sbin"
for b in munged slurmctld slurmd sbatch sinfo squeue; do
  command -v "$b" >/dev/null || { echo "farm: $b not installed (tools/install-deps); skipped"; exit 77; }
done

tmp="$(mktemp -d /tmp/vkray-farm-test.XXXXXX)"
# A cluster of its own, beside any other the user runs.
export VKRAY_SLURM_LOCAL_STATE="$tmp/slurm-local.state"
unset SLURM_CONF
cleanup() {
  "$src/tools/farm/slurm-local" stop || true
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() {
  echo "farm: FAIL: $*" >&2
  exit 1
}

scene="$src/scenes/showcase-turntable.json"
size=(--width 96 --height 64)
# A bad command line is refused before anything is submitted: zero tiles is no tiling.
rc=0
"$src/tools/farm/submit-slurm" "$scene" --frames 0-0 --tiles 0 --out "$tmp/zero" --vkray "$vkray" 2>"$tmp/zero.err" || rc=$?
[ "$rc" = 2 ] && grep -q "^submit-slurm: --tiles: expected a whole number >= 1, got '0'$" "$tmp/zero.err" ||
  fail "--tiles 0: expected exit 2 naming --tiles, got $rc: $(cat "$tmp/zero.err")"

# eval "$(...)" would succeed on a failed start (eval of nothing): take its output first.
started="$("$src/tools/farm/slurm-local" start)" || fail "tools/farm/slurm-local start failed (its message is above)"
eval "$started"

# The oracle: one local process, every frame, and frame 4's tiles.
mkdir -p "$tmp/local"
"$vkray" render "$scene" --frames 0-5 "${size[@]}" -q -o "$tmp/local/frame_%04d.png"
for i in 1 2 3; do
  "$vkray" render "$scene" --frame 4 --tile "$i/3" "${size[@]}" -q -o "$(printf '%s/local/frame_0004.tile_%03d.pfm' "$tmp" "$i")"
done

"$src/tools/farm/submit-slurm" "$scene" --frames 0-5 --chunk 2 --out "$tmp/chunks" --render-args "${size[*]}" \
  --vkray "$vkray" >"$tmp/chunks.out"
grep -Eq '^slurm job: [0-9]+$' "$tmp/chunks.out" || fail "no 'slurm job: ID' line: $(cat "$tmp/chunks.out")"
for f in 0 1 2 3 4 5; do
  name="$(printf 'frame_%04d.png' "$f")"
  cmp "$tmp/local/$name" "$tmp/chunks/$name" || fail "chunks: $name differs from the local render"
done
[ "$(ls "$tmp/chunks" | wc -l)" = 6 ] || fail "chunks: expected 6 files, got: $(ls "$tmp/chunks")"

"$src/tools/farm/submit-slurm" "$scene" --frames 4-4 --tiles 3 --keep-tiles --out "$tmp/tiles" \
  --render-args "${size[*]}" --vkray "$vkray" >/dev/null
cmp "$tmp/local/frame_0004.png" "$tmp/tiles/frame_0004.png" || fail "tiles: merged frame 4 differs from the whole render"
for i in 1 2 3; do
  name="$(printf 'frame_0004.tile_%03d.pfm' "$i")"
  cmp "$tmp/local/$name" "$tmp/tiles/tiles/$name" || fail "tiles: $name differs from the local tile"
done

# A task that fails once is requeued; one that always fails is named, and the run fails.
cat >"$tmp/flaky-vkray" <<FLAKY
#!/bin/bash
if [[ " \$* " == *" --frames 2-3 "* ]] && mkdir "$tmp/failed-once" 2>/dev/null; then exit 3; fi
if [[ " \$* " == *" --frames 4-5 "* ]] && [ -n "\${FARM_TEST_ALWAYS_FAIL:-}" ]; then exit 3; fi
exec "$vkray" "\$@"
FLAKY
chmod +x "$tmp/flaky-vkray"
"$src/tools/farm/submit-slurm" "$scene" --frames 0-5 --chunk 2 --out "$tmp/requeue" --render-args "${size[*]}" \
  --vkray "$tmp/flaky-vkray" >"$tmp/requeue.out" 2>"$tmp/requeue.err" || fail "requeue: $(cat "$tmp/requeue.err")"
[ "$(grep -c '^slurm job: ' "$tmp/requeue.out")" = 2 ] || fail "requeue: expected a second job for the failed task"
cmp "$tmp/local/frame_0003.png" "$tmp/requeue/frame_0003.png" || fail "requeue: frame 3 differs"
if FARM_TEST_ALWAYS_FAIL=1 "$src/tools/farm/submit-slurm" "$scene" --frames 0-5 --chunk 2 --out "$tmp/broken" \
  --render-args "${size[*]}" --vkray "$tmp/flaky-vkray" >/dev/null 2>"$tmp/broken.err"; then
  fail "broken: a task that always fails did not fail the run"
fi
grep -q 'frames 4-5 failed twice' "$tmp/broken.err" || fail "broken: message does not name frames 4-5: $(cat "$tmp/broken.err")"
echo "farm: ok"
