#!/usr/bin/env bash
# What an operator sees (issue 15 item 7): on a terminal, one bar with items done/total,
# a collection percentage that never goes back, elapsed time and an ETA, and no log line
# ever glued onto the bar; without a terminal (cron), no bar, and each publication line
# says how far the run has come.
source "$(dirname "$0")/../lib.sh"
command -v script >/dev/null || { echo "SKIP: no script(1) to give the run a terminal"; exit 77; }

mkdir -p "$TMP/in"
cp "$SCANS/bun_zipper_res4.ply" "$SCANS/rocker_arm.ply" "$SCANS/cow.ply" "$TMP/in/"
write_config "$TMP/c.ini" "$TMP/in" "$TMP/work" "$TMP/out"

# On a terminal (script(1) gives the run a pseudo-terminal of 120 columns).
script -qec "stty cols 120 2>/dev/null; '$SCANLOD' run '$TMP/c.ini' -v" "$TMP/tty.txt" >/dev/null
check "terminal run exits 0" grep -q "exit 0" "$TMP/tty.txt"
check "the bar, its percentages and the log lines as a person sees them" python3 - "$TMP/tty.txt" <<'EOF'
import re, sys
text = open(sys.argv[1], "rb").read().decode("utf-8", "replace")
bars, glued = [], []
for line in text.split("\n"):
    segments = line.split("\r")
    for i, seg in enumerate(segments):
        seg = seg.replace("\x1b[K", "")
        if seg.startswith("["):
            bars.append(seg)
        # A log line must begin a segment of its own: never after bar text on one line.
        m = re.search(r"\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z (INFO|WARN|ERROR|DEBUG)", seg)
        if m and m.start() > 0 and seg[:m.start()].strip():
            glued.append(seg[:80])
bar = re.compile(r"^\[[#.]{10}\] (\d+)/(\d+) items (\d+)%  \d+:\d\d( ETA \d+:\d\d)?  \S+ \w+( \d+%)?$")
bad = [b for b in bars if not bar.match(b.rstrip())]
fail = []
if len(bars) < 5: fail.append("only %d bars drawn" % len(bars))
if bad: fail.append("malformed bars: %r" % bad[:3])
if glued: fail.append("log lines glued onto the bar: %r" % glued[:3])
totals = {int(bar.match(b.rstrip()).group(2)) for b in bars if bar.match(b.rstrip())}
if totals != {3}: fail.append("totals %s, not the 3 items" % sorted(totals))
percents = [int(bar.match(b.rstrip()).group(3)) for b in bars if bar.match(b.rstrip())]
if any(b < a for a, b in zip(percents, percents[1:])): fail.append("percent went back: %s" % percents)
if not any(" ETA " in b for b in bars): fail.append("no ETA ever shown")
print("\n".join(fail) or "%d bars, %d%% .. %d%%" % (len(bars), percents[0], percents[-1]), file=sys.stderr)
sys.exit(1 if fail else 0)
EOF

# Without a terminal: no bar escape codes at all, and the progress on the publish lines.
rm -rf "$TMP/work" "$TMP/out"
run_scanlod run "$TMP/c.ini"
check "plain run exits 0 (got $rc)" [ "$rc" -eq 0 ]
check "no bar or escape code on a file" bash -c '! grep -qP "\r|\x1b|\[[#.]{10}\]" <<<"$1"' _ "$err"
for k in 1 2 3; do
  check "publish line $k says how far the run has come" grep -qE "published .* \($k/3 items, [0-9]+ %, [0-9]+:[0-9]{2} elapsed" <<<"$err"
done
finish
