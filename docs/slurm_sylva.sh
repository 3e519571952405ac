#!/usr/bin/env bash
# Slurm batch script for a regional Sylva run over MPI (issue 17; docs/SCALING.md).
# One tile per MPI rank; the run directory holds the files of one process, byte for byte,
# except the checkpoint (one file per rank in OUT/checkpoint/) and the inventories (one part per
# rank: OUT/inventory/year_NNNN/part-RRRRR.parquet, read as one dataset by sylva, pyarrow and
# DuckDB). Every rank writes into OUT (its checkpoint and its inventory parts), so OUT must be on a file
# system all ranks share and can write (the cluster's parallel or network file system). In a
# fresh run each rank holds only its band and tile of the site and its own tile's trees (issue
# 37 rounds 32-33; with [[management]] too since round 36; docs/SCALING.md, "What a rank
# holds"), and so does a RESUMED run since round 37 (this script adds --resume when OUT holds a
# checkpoint): every rank reads only the checkpoint files of the old tiles over its own, on
# any number of ranks (1-4 files on a halved or doubled count), so the rank count may change
# between restarts without sizing rank 0 for the whole world. Sizing
# from the measured costs (docs/SCALING.md, "Round 23 update" and its round 26
# line): the site costs each rank about 20 KiB per hectare (rank 0 about 30 KiB: it keeps the
# whole world; 100,000 ha: ~1.9 GiB a rank, ~2.9 GiB on rank 0; 1,000,000 ha: ~19 GiB, ~29 GiB
# on rank 0, so there run one rank per node with --cpus-per-task=32 and --mem=0, not 8 ranks a
# node), the trees about 130 bytes each (2,400 per ha at year 100) divided over the ranks, and
# the CPU about 0.28 microseconds per tree-year (100,000 ha x 100 years: ~1 core-hour), so
# --time is set by the output years (each rank writes its own inventory parts since issue 37
# round 24, ~115 B a tree for a GeoPackage year), not the simulation.
# Build once on the cluster with MPI:
#   cargo build --release --features mpi      (needs libopenmpi-dev or the site's MPI, libclang)
# Submit:  sbatch docs/slurm_sylva.sh scenarios/region.toml /scratch/$USER/region
#SBATCH --job-name=sylva-region
#SBATCH --nodes=4
#SBATCH --ntasks-per-node=4          # 16 ranks = 16 tiles (the tiles are cut closest to square)
#SBATCH --cpus-per-task=8            # rayon threads inside each rank
#SBATCH --mem-per-cpu=2G
#SBATCH --time=04:00:00
set -euo pipefail
SCENARIO=${1:?usage: sbatch slurm_sylva.sh SCENARIO.toml OUT_DIR}
OUT=${2:?usage: sbatch slurm_sylva.sh SCENARIO.toml OUT_DIR}
# a run already started in OUT continues from its checkpoint (on any number of ranks): the
# per-rank checkpoints of a tiled run (OUT/checkpoint/manifest.toml; each rank reads the files
# of the old tiles its tile overlaps: its own file when the number of ranks is the same) or one
# process's OUT/checkpoint.bin (read by every rank, which keeps its tile's part)
RESUME=()
if [ -f "$OUT/checkpoint/manifest.toml" ] || [ -f "$OUT/checkpoint.bin" ]; then RESUME=(--resume); fi
# srun starts one `sylva` per task; Open MPI's PMIx (or PMI2) tells each its rank
srun --mpi=pmix ./target/release/sylva simulate "$SCENARIO" --out "$OUT" \
  --threads "${SLURM_CPUS_PER_TASK:-1}" "${RESUME[@]}"
