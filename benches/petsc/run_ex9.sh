#!/usr/bin/env bash
# Usage: benches/petsc/run_ex9.sh BIN GRID [NPROC]   (GRID = 4*2^K + 1: 257, 513, 1025, 2049, 4097)
# Runs PETSc's ex9 (Bueler's radial obstacle on [-2,2]^2, 5-point FD, SNESVINEWTONRSLS; or BIN =
# ex9_linear of build.sh, the same without the obstacle) the way its header recommends
# ("full-cycle multigrid"): grid sequencing from ex9's default 5x5 coarse grid (also what PETSc's
# own ex9 tests use) with K = log2((GRID-1)/4) refinements and PCMG (which then has K+1 levels on
# the final grid), OMP_NUM_THREADS=1, on NPROC MPI processes (default 1).
# NPROC = 1: one process (singleton, no mpiexec) under /usr/bin/time -v: its wall clock and peak
# resident set. NPROC > 1: `mpiexec -n NPROC` (with --oversubscribe only when NPROC exceeds the
# physical cores, which Open MPI counts as its slots) under /usr/bin/time for the wall clock of
# the whole job, launch included; every rank runs under its own /usr/bin/time, which writes the
# rank's peak resident set (%M) to a file of its own (named by its pid), and the peak memory is
# the sum over the ranks: /usr/bin/time around mpiexec would see only the launcher's, and
# getrusage(RUSAGE_CHILDREN) gives the largest child's, not the sum. The sum of the per-rank
# peaks bounds the job's simultaneous peak from above (the ranks of this SPMD run peak
# together); mpiexec's own few MiB are not counted.
# Prints ONE JSON line on stdout; the PETSc output goes to the log file $EX9_LOG (default: next
# to BIN, NAME_GRID_NPROC.log).
set -euo pipefail
[ $# -eq 2 ] || [ $# -eq 3 ] || { echo "usage: $0 BIN GRID [NPROC]" >&2; exit 2; }
BIN=$1 GRID=$2 NPROC=${3:-1} N0=5
die() { echo "run_ex9.sh: $*" >&2; exit 1; }
[ -x "$BIN" ] || die "no executable ex9 at '$BIN' (run benches/petsc/build.sh OUTDIR)"
[ -x /usr/bin/time ] || die "/usr/bin/time missing (run benches/petsc/install.sh)"
[[ "$NPROC" =~ ^[1-9][0-9]*$ ]] || die "NPROC must be a positive integer, got '$NPROC'"
# K with (N0-1)*2^K + 1 = GRID
K=0
while [ $(((N0 - 1) * (1 << K) + 1)) -lt "$GRID" ]; do K=$((K + 1)); done
[ $(((N0 - 1) * (1 << K) + 1)) -eq "$GRID" ] || die "GRID=$GRID is not 4*2^K+1 (e.g. 257, 513, 1025)"
LOG=${EX9_LOG:-$(dirname "$BIN")/$(basename "$BIN")_${GRID}_$NPROC.log}
TIMES=$(mktemp); RSS=$(mktemp -d); trap 'rm -rf "$TIMES" "$RSS"' EXIT
# The -*_converged_reason options only print one line per solve (counted below).
ARGS=(-da_grid_x "$N0" -da_grid_y "$N0" -snes_grid_sequence "$K" -pc_type mg
      -snes_converged_reason -ksp_converged_reason)
rc=0
if [ "$NPROC" -eq 1 ]; then
  CMD="OMP_NUM_THREADS=1 $BIN ${ARGS[*]}"
  OMP_NUM_THREADS=1 /usr/bin/time -v -o "$TIMES" "$BIN" "${ARGS[@]}" >"$LOG" 2>&1 || rc=$?
else
  command -v mpiexec >/dev/null || die "mpiexec missing (run benches/petsc/install.sh)"
  MPI=(-n "$NPROC")
  cores=$(lscpu -p=core,socket 2>/dev/null | grep -v '^#' | sort -u | wc -l)
  [ "$cores" -ge "$NPROC" ] || MPI+=(--oversubscribe)
  if [ "$(id -u)" = 0 ]; then export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1; fi
  CMD="OMP_NUM_THREADS=1 mpiexec ${MPI[*]} $BIN ${ARGS[*]}"
  # each rank: /usr/bin/time -f %M -o RSS/rank.PID BIN ARGS (bash execs time, so PID is unique)
  OMP_NUM_THREADS=1 /usr/bin/time -v -o "$TIMES" mpiexec "${MPI[@]}" \
    bash -c 'exec /usr/bin/time -f %M -o "$0/rank.$$" "$@"' "$RSS" "$BIN" "${ARGS[@]}" \
    >"$LOG" 2>&1 || rc=$?
fi
[ "$rc" -eq 0 ] || { tail -n 20 "$LOG" >&2; die "ex9 failed (exit $rc), log in $LOG"; }
# Parse the log. With -snes_grid_sequence every level prints its own "Nonlinear solve ..." line
# (coarsest first, the final grid last, unindented); the "Linear solve ... iterations N" lines
# (-ksp_converged_reason, one per Newton step) before it belong to that level. KSP iterations
# are summed from those lines (-snes_view's "total number of linear solver iterations" covers
# only the final level).
read -r SNES SNES_F KSP KSP_F NLEV BAD EMEAN EMAX < <(awk '
  /Linear solve (converged|did not converge)/ { k += $NF; kl += $NF }
  /Nonlinear solve converged/ { s += $NF; sf = $NF; kf = kl; kl = 0; n++ }
  /Nonlinear solve did not converge/ { bad++ }
  /^errors on/ { gsub(",", ""); for (i = 1; i <= NF; i++) { if ($i == "av") em = $(i + 3); if ($i ~ /_inf$/) ex = $(i + 2) } }
  END { print s + 0, sf + 0, k + 0, kf + 0, n + 0, bad + 0, (em == "" ? "-" : em), (ex == "" ? "-" : ex) }' "$LOG")
[ "$BAD" -eq 0 ] || die "a nonlinear solve did not converge, see $LOG"
[ "$NLEV" -eq $((K + 1)) ] || die "expected $((K + 1)) converged nonlinear solves, found $NLEV, see $LOG"
grep -q "^errors on $GRID x $GRID grid" "$LOG" || die "no 'errors on $GRID x $GRID grid' line in $LOG"
[ "$EMEAN" != - ] && [ "$EMAX" != - ] || die "cannot parse the errors line in $LOG"
# /usr/bin/time: "Elapsed (wall clock) time (h:mm:ss or m:ss): 0:05.09", "Maximum resident set size (kbytes): 939760"
SECS=$(awk -F': ' '/Elapsed \(wall clock\)/ { n = split($2, t, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + t[i]; printf "%.2f", s }' "$TIMES")
if [ "$NPROC" -eq 1 ]; then
  MIB=$(awk -F': ' '/Maximum resident set size/ { printf "%.1f", $2 / 1024 }' "$TIMES")
else
  n=$(find "$RSS" -name 'rank.*' | wc -l)
  [ "$n" -eq "$NPROC" ] || die "expected $NPROC per-rank peak memory files, found $n"
  MIB=$(cat "$RSS"/rank.* | awk '{ s += $1 } END { printf "%.1f", s / 1024 }')
fi
[ -n "$SECS" ] && [ -n "$MIB" ] || die "cannot parse /usr/bin/time -v output"
printf '{"grid":%d,"processes":%d,"unknowns":%d,"levels":%d,"n0":%d,"seconds":%s,"peak_mib":%s,"snes_iterations":%d,"snes_iterations_final":%d,"ksp_iterations":%d,"ksp_iterations_final":%d,"err_max":%s,"err_mean":%s,"command":"%s"}\n' \
  "$GRID" "$NPROC" $((GRID * GRID)) "$K" "$N0" "$SECS" "$MIB" "$SNES" "$SNES_F" "$KSP" "$KSP_F" "$EMAX" "$EMEAN" "${CMD//\"/\\\"}"
