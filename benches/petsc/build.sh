#!/usr/bin/env bash
# Usage: benches/petsc/build.sh OUTDIR
# Copies PETSc's snes/tutorials/ex9.c from the Debian examples package into OUTDIR (it is not
# part of this repository) and compiles OUTDIR/ex9 with mpicc -O2 against the system PETSc,
# only if the binary is missing or older than the source. Last line of stdout: the binary path.
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
BIN=$OUT/ex9
if [ ! -x "$BIN" ] || [ "$OUT/ex9.c" -nt "$BIN" ]; then
  CC=${MPICC:-$(pkg-config --variable=ccompiler PETSc)}   # mpicc for Debian's PETSc
  echo "building $BIN (PETSc $(pkg-config --modversion PETSc), $CC -O2)" >&2
  # shellcheck disable=SC2046  # word splitting of the pkg-config flags is intended
  "$CC" -O2 $(pkg-config --cflags PETSc) "$OUT/ex9.c" -o "$BIN" $(pkg-config --libs PETSc) -lm >&2
fi
echo "$BIN"
