#!/usr/bin/env bash
# Crash safety (reliability T1): a run over 7 items is killed with SIGKILL at 24 random
# moments; after every kill no record may vouch for a file that does not match it
# (`scanlod verify`), and every published item folder holds exactly the clean run's files,
# byte for byte (timings.json aside): publication is atomic per item. Resumed to the end,
# artifacts and publications are byte-identical to the clean run. The export writes every
# kind of file (PLY, GLB, thumbnails, measured fidelity), on two levels to keep it short.
# SCANLOD_CRASH_KILLS overrides the number of kills (nightly: 200). SCANLOD_LIGHT=1 (the
# sanitizer pass): 3 small items, one nested, and 12 kills.
source "$(dirname "$0")/../lib.sh"
kills=${SCANLOD_CRASH_KILLS:-24}
scans=("$SCANS"/*.ply)
nested=(cow fandisk)
if light; then
  kills=${SCANLOD_CRASH_KILLS:-12}
  scans=("$SCANS/bun_zipper_res4.ply" "$SCANS/bun_zipper_res3.ply")
  nested=(cow)
  echo "LIGHT: $kills kills of a 3-item run; 24 kills of 7 items in the Release pass"
fi

mkdir -p "$TMP/in/nested"
i=0
for f in "${scans[@]}"; do
  cp "$f" "$TMP/in/item$i.ply"; i=$((i + 1))
done
for n in "${nested[@]}"; do cp "$SCANS/$n.ply" "$TMP/in/nested/$n.ply"; done
items=$(find "$TMP/in" -name '*.ply' | wc -l)
check "at least 3 items, one nested ($items)" [ "$items" -ge 3 ]

export_lines=("[levels]" "percents = 20,100" "budgets =" "[export]" "formats = ply,glb"
              "thumbnail_size = 48" "fidelity = true" "fidelity_samples = 5000")
# The sanitizer pass: the refine stage without its fit (most of a light run's CPU under
# ASan); every run here has the same config, so the byte identity it checks is the same.
light && export_lines+=("[refine]" "fit = false")
write_config "$TMP/ref.ini" "$TMP/in" "$TMP/ref-work" "$TMP/ref-out" "${export_lines[@]}"
start=$(date +%s%N)
run_scanlod run "$TMP/ref.ini" -q
clean_ns=$(( $(date +%s%N) - start ))
check "clean run exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
ref=$(tree_digest "$TMP/ref-work" "$TMP/ref-out")
run_scanlod status "$TMP/ref.ini"
total=$(( ($(wc -l <<<"$out") - 1) * items )) # stage results of a finished collection

write_config "$TMP/kill.ini" "$TMP/in" "$TMP/work" "$TMP/out" "${export_lines[@]}"
bad_publications=0
published_seen=0
unverified=0
done_at_kill=()
for k in $(seq 1 "$kills"); do
  # Uniform over the clean run's duration: early kills land in the scan, late ones in
  # commits and publication.
  delay_ms=$(( (RANDOM * 32768 + RANDOM) % (clean_ns / 1000000 + 1) ))
  "$SCANLOD" run "$TMP/kill.ini" -q >/dev/null 2>&1 &
  pid=$!
  sleep "$(printf '0.%03d' "$delay_ms")" 2>/dev/null || sleep 0
  [ "$delay_ms" -ge 1000 ] && sleep $((delay_ms / 1000))
  kill -9 "$pid" 2>/dev/null || true
  wait "$pid" 2>/dev/null || true
  done_now=$( (find "$TMP/work/queue" -path '*/done/*' -type f 2>/dev/null || true) | wc -l)
  done_at_kill+=("$done_now")
  # Every published item folder must be complete and equal to the clean run's.
  while IFS= read -r -d '' f; do
    rel=$(dirname "${f#"$TMP/out/"}")
    diff -rq -x timings.json "$TMP/out/$rel" "$TMP/ref-out/$rel" >&2 ||
      { bad_publications=$((bad_publications + 1)); echo "differs after kill $k: $rel" >&2; }
  done < <(find "$TMP/out" -name report.json ! -path '*/.*' -print0 2>/dev/null)
  published_seen=$((published_seen + $( (find "$TMP/out" -name report.json ! -path '*/.*' 2>/dev/null || true) | wc -l)))
  run_scanlod verify "$TMP/kill.ini"
  [ "$rc" -eq 0 ] || { unverified=$((unverified + 1)); echo "verify after kill $k: $out $err" >&2; }
  # Once everything is done, start over, so that the next kills land in real work again.
  if [ "$done_now" -ge "$total" ]; then rm -rf "$TMP/work" "$TMP/out"; fi
done
echo "stage results done at each kill: ${done_at_kill[*]} (of $total)" >&2
# With many kills some land after a publication (with a handful, all may land before).
[ "$kills" -lt 10 ] || check "some kills found published items to compare ($published_seen)" [ "$published_seen" -gt 0 ]
check "no published item folder ever differed from the clean run ($bad_publications)" [ "$bad_publications" -eq 0 ]
check "every record verified after every kill ($unverified failures)" [ "$unverified" -eq 0 ]

run_scanlod run "$TMP/kill.ini" -q
check "resume after $kills kills exits 0 (got $rc: $err)" [ "$rc" -eq 0 ]
check "resumed artifacts byte-identical to the clean run" [ "$ref" = "$(tree_digest "$TMP/work" "$TMP/out")" ]
leftovers=$(find "$TMP/work" "$TMP/out" -name '.*' ! -name '.' | wc -l)
check "no temp files left behind after the resume ($leftovers)" [ "$leftovers" -eq 0 ]
finish
