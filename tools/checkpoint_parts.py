#!/usr/bin/env python3
"""The parts of a Sylva checkpoint (layouts 14/15, sim::checkpoint): decodes the zstd body with the
zstd CLI, walks the layout (identity, trees, seed grids, cohorts, the rest) and compresses each part
apart with `zstd -1` (the checkpoint's level), printing bytes a tree, a seed cell and a cohort: the
figures behind job::disk::checkpoint_bytes (round 46, BENCHMARKS.md). Usage: python3
tools/checkpoint_parts.py RUN/checkpoint.bin. Needs the zstd command; 11 f32 tree columns (trees.rs N_F32_COLUMNS)."""
import struct, subprocess, sys
b = open(sys.argv[1], 'rb').read()
body = b[20:-4]
raw = subprocess.run(['zstd', '-d', '-c'], input=body, capture_output=True, check=True).stdout
pos = 0
def u64():
    global pos
    v = struct.unpack_from('<Q', raw, pos)[0]; pos += 8; return v
def skip(n):
    global pos
    s = raw[pos:pos+n]; pos += n; return s
n = u64()
for _ in range(n):
    skip(u64()); skip(u64())
start_ident = 0; end_ident = pos
year = u64(); next_id = u64(); nt = u64(); t0 = pos - 16
skip(8*nt)
ns = u64(); skip(2*ns)
for _ in range(11):
    m = u64(); skip(4*m)
t1 = pos
ng = u64(); cells = 0
for _ in range(ng):
    m = u64(); cells += m; skip(4*m)
s1 = pos
for _ in range(5): u64()
c0 = pos
m = u64(); skip(4*m); ncoh = m
m = u64(); skip(4*m)
m = u64(); skip(4*m)
for _ in range(3):
    m = u64(); skip(4*m)
m = u64(); skip(4*m)
c1 = pos
def z(s):
    return len(subprocess.run(['zstd', '-1', '-c'], input=s, capture_output=True, check=True).stdout)
parts = {'identity': raw[:end_ident], 'trees': raw[t0:t1], 'seeds': raw[t1:s1], 'cohorts': raw[c0:c1], 'rest': raw[c1:]}
print(f'file {len(b)} B, raw {len(raw)} B, year {year}, trees {nt}, seed grids {ng} with {cells} cells, cohorts {ncoh}')
for k, v in parts.items():
    zz = z(v)
    extra = {'trees': f' {zz/nt:.2f} B/tree', 'seeds': f' {zz/cells:.3f} B/seed cell', 'cohorts': f' {zz/max(ncoh,1):.2f} B/cohort'}.get(k, '')
    print(f'  {k}: raw {len(v)} B, zstd -1 {zz} B{extra}')
