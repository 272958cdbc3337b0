#!/usr/bin/env bash
# Usage: benches/petsc/build.sh OUTDIR
# Copies PETSc's snes/tutorials/ex9.c from the Debian examples package into OUTDIR (it is not
# part of this repository) and compiles OUTDIR/ex9 with mpicc -O2 against the system PETSc,
# only if the binary is missing or older than the source. Also OUTDIR/ex9_linear, the same
# program without the obstacle (the linear solve of the cost ratio R): derived from ex9.c by
# dropping the bounds (the SNESVISetComputeVariableBounds call) and using Newton line search
# (SNESNEWTONLS) instead of the VI solver SNESVINEWTONRSLS, so the same mesh, Dirichlet data,
# grid sequencing, Krylov method and multigrid solve -Δu = 0. Last line of stdout: the path of
# ex9 (ex9_linear is next to it).
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 OUTDIR" >&2; exit 2; }
OUT=$1
v=$(pkg-config --modversion PETSc | cut -d. -f1,2) ||
  { echo "$0: PETSc not found by pkg-config; run benches/petsc/install.sh" >&2; exit 1; }
SRC=${EX9_SRC:-/usr/share/petsc/$v/share/petsc/examples/src/snes/tutorials/ex9.c}
[ -f "$SRC" ] || { echo "$0: $SRC missing; run benches/petsc/install.sh" >&2; exit 1; }
mkdir -p "$OUT"
# copy only when the content changed, so an unchanged source keeps its older mtime
cmp -s "$SRC" "$OUT/ex9.c" || cp "$SRC" "$OUT/ex9.c"
# the linear variant: exactly one bounds call and one SNESSetType to the VI type in ex9.c, or the derivation is wrong
[ "$(grep -c 'SNESVISetComputeVariableBounds(snes' "$OUT/ex9.c")" -eq 1 ] &&
  [ "$(grep -c 'SNESSetType(snes, SNESVINEWTONRSLS)' "$OUT/ex9.c")" -eq 1 ] ||
  { echo "$0: $SRC does not have the one bounds call and VI type that ex9_linear removes" >&2; exit 1; }
sed -e '/SNESVISetComputeVariableBounds(snes/d' -e 's/SNESSetType(snes, SNESVINEWTONRSLS)/SNESSetType(snes, SNESNEWTONLS)/' \
  "$OUT/ex9.c" >"$OUT/ex9_linear.c.new"
if cmp -s "$OUT/ex9_linear.c.new" "$OUT/ex9_linear.c"; then rm "$OUT/ex9_linear.c.new"
else mv "$OUT/ex9_linear.c.new" "$OUT/ex9_linear.c"; fi
CC=${MPICC:-$(pkg-config --variable=ccompiler PETSc)}   # mpicc for Debian's PETSc
for name in ex9 ex9_linear; do
  BIN=$OUT/$name
  if [ ! -x "$BIN" ] || [ "$OUT/$name.c" -nt "$BIN" ]; then
    echo "building $BIN (PETSc $(pkg-config --modversion PETSc), $CC -O2)" >&2
    # shellcheck disable=SC2046  # word splitting of the pkg-config flags is intended
    "$CC" -O2 $(pkg-config --cflags PETSc) "$OUT/$name.c" -o "$BIN" $(pkg-config --libs PETSc) -lm >&2
  fi
done
echo "$OUT/ex9"
