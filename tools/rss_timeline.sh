#!/bin/bash
# Memory over time of a command (issue 34): runs `cmd...`, appends to LOG a line
# `<unix time> RSS <kB>` every second (VmRSS of the process) and each line the command writes
# to stderr as `<unix time> ERR <line>` (sylva's phase lines), and `rc=<exit status>` at the end.
# Usage: tools/rss_timeline.sh LOG cmd...   e.g. tools/rss_timeline.sh rss.log target/release/sylva run --out out
# SAMPLE_S=0.2 samples five times a second.
# Peak: awk '/RSS/{if($3>m)m=$3}END{print m}' LOG
# SPDX-License-Identifier: MIT OR Apache-2.0
LOG=$1; shift
"$@" 2> >(while IFS= read -r l; do echo "$(date +%s.%N | cut -c1-14) ERR $l"; done >> $LOG) &
PID=$!
while kill -0 $PID 2>/dev/null; do
  R=$(awk '/VmRSS/{print $2}' /proc/$PID/status 2>/dev/null); echo "$(date +%s.%N | cut -c1-14) RSS $R" >> $LOG; sleep ${SAMPLE_S:-1}
done
wait $PID; echo "rc=$?" >> $LOG
