#!/usr/bin/env python3
"""Runs a stand bench binary (benches/stand.rs), samples its /proc/PID/stat and status every
50 ms, and prints the process's CPU time (user, sys), minor page faults and peak RSS at the end
of the first call (the bench's "first call s" after its start) and at its last sample
(BENCHMARKS.md, round 36). Usage: SYLVA_STAND_FULL=1 SYLVA_STAND_ONCE=1 RAYON_NUM_THREADS=2
python3 tools/stand_call_cpu.py BENCH --bench"""
import subprocess, sys, time, os, re
tck = os.sysconf('SC_CLK_TCK')
t0 = time.monotonic()
p = subprocess.Popen(sys.argv[1:], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
samples = []
def sample():
    try:
        f = open(f'/proc/{p.pid}/stat').read().rsplit(')', 1)[1].split()
        st = open(f'/proc/{p.pid}/status').read()
        rss = int(re.search(r'VmRSS:\s+(\d+)', st).group(1)); hwm = int(re.search(r'VmHWM:\s+(\d+)', st).group(1))
        # fields after ')': state=0, ppid=1, ..., minflt=7, majflt=9, utime=11, stime=12
        samples.append((time.monotonic() - t0, int(f[11]) / tck, int(f[12]) / tck, int(f[7]), rss, hwm))
    except Exception:
        pass
while p.poll() is None:
    sample()
    time.sleep(0.05)
out = p.stdout.read()
print(out, end='')
m = re.search(r'^\| \d+ \| \d+ \| \d+ \| \d+ \| \d+ \| \d+ \| \d+ \| ([0-9.]+) \|', out, re.M)
T = float(m.group(1))
before = [s for s in samples if s[0] <= T]
s = before[-1]
print(f"at end of first call ({T:.2f} s; sample at {s[0]:.2f} s): user {s[1]:.2f} + sys {s[2]:.2f} = {s[1]+s[2]:.2f} CPU-s, minor faults {s[3]}, RSS {s[4]} kB, peak RSS {s[5]} kB")
e = samples[-1]
print(f"last sample ({e[0]:.2f} s): user {e[1]:.2f} + sys {e[2]:.2f} = {e[1]+e[2]:.2f} CPU-s, minor faults {e[3]}, peak RSS {e[5]} kB")
