#!/usr/bin/env bash
# The merge after slurm_campaign.sbatch: renames every part's shards from
# OUTDIR.parts/* into OUTDIR, then runs `rtpipe campaign CONFIG OUTDIR`,
# which checks every shard's footer against the configuration (another
# campaign's is refused), writes OUTDIR/_campaign.parquet, runs any shard
# still missing (a part that failed) and reports what it skipped. The parts'
# directories are removed once empty.
#
#   sbatch --dependency=afterok:JOBID slurm_merge.sh CONFIG OUTDIR
#   bash slurm_merge.sh CONFIG OUTDIR        # or by hand, on any node
#SBATCH --job-name=rtpipe-merge
#SBATCH --cpus-per-task=1
#SBATCH --time=00:30:00
set -euo pipefail
if [ $# -ne 2 ]; then
  echo "usage: $0 CONFIG OUTDIR" >&2
  exit 2
fi
config=$1
out=${2%/}
rtpipe=${RTPIPE:-rtpipe}
# Checks OUTDIR before anything moves: another campaign's is refused.
"$rtpipe" campaign "$config" "$out" --plan
mkdir -p "$out"
shopt -s nullglob
for part in "$out.parts"/*/; do
  # Only the part's own shards (its _campaign.parquet is OUTDIR's too);
  # a name OUTDIR already has is left where it is (-n), never replaced.
  for shard in "$part"shard-*.parquet; do
    mv -n -- "$shard" "$out/"
  done
  rm -f -- "$part/_campaign.parquet"
  rmdir -- "$part" 2>/dev/null || echo "kept $part: it holds more than its shards" >&2
done
rmdir -- "$out.parts" 2>/dev/null || true
exec "$rtpipe" campaign "$config" "$out" --jobs "${SLURM_CPUS_PER_TASK:-1}"
