#!/usr/bin/env bash
# Regenerate every meshes/*.msh from its .geo source with gmsh (ASCII MSH 4.1,
# single thread, Frontal-Delaunay), print a statistics table and write it into
# meshes/README.md (between the MESH TABLE markers).
#
# Usage: bash meshes/generate.sh [--check]
#   --check   additionally mesh every .geo a second time into a temporary
#             directory and verify that the two outputs are byte-identical.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
cd "$here"

check=0
for arg in "$@"; do
  case "$arg" in
    --check) check=1 ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    *) echo "generate.sh: unknown argument '$arg'" >&2; exit 2 ;;
  esac
done

# --- gmsh -------------------------------------------------------------------
if ! command -v gmsh >/dev/null 2>&1; then
  echo "generate.sh: gmsh not found; installing the Debian package 'gmsh'" >&2
  if [ "$(id -u)" -eq 0 ]; then
    SUDO=""
  elif command -v sudo >/dev/null 2>&1; then
    SUDO="sudo"
  else
    echo "generate.sh: ERROR: gmsh is missing, and we are neither root nor have sudo." >&2
    echo "             Install it yourself (e.g. 'apt-get install -y gmsh') and rerun." >&2
    exit 1
  fi
  if ! command -v apt-get >/dev/null 2>&1; then
    echo "generate.sh: ERROR: gmsh is missing and apt-get is not available; install gmsh (>= 4.8) by other means." >&2
    exit 1
  fi
  if ! { $SUDO apt-get update && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y gmsh; }; then
    echo "generate.sh: ERROR: 'apt-get install -y gmsh' failed; install gmsh by hand and rerun." >&2
    exit 1
  fi
  command -v gmsh >/dev/null 2>&1 || { echo "generate.sh: ERROR: gmsh still not on PATH after install" >&2; exit 1; }
fi

PY="$(command -v python3 || true)"
[ -n "$PY" ] || PY=/usr/bin/python3
[ -x "$PY" ] || { echo "generate.sh: ERROR: python3 is needed for mesh_stats.py" >&2; exit 1; }

GMSH_VERSION="$(gmsh --version 2>&1 | tail -n 1)"

# Fixed order, fixed options (the .geo files also set these).
GEOS=(test1_1 test1_2 test1_3 test1_4
      test2tri_1 test2tri_2 test2tri_3 test2tri_4
      test3_1 test3_2 test3_3 test3_4)
GMSH_OPTS=(-2 -nt 1 -format msh41 -v 2)

mesh_one() {  # $1 = geo, $2 = output msh
  gmsh "${GMSH_OPTS[@]}" "$1" -o "$2" >/dev/null
}

echo "generate.sh: gmsh $GMSH_VERSION" >&2
for g in "${GEOS[@]}"; do
  echo "generate.sh: meshing $g.geo" >&2
  mesh_one "$g.geo" "$g.msh"
done

if [ "$check" -eq 1 ]; then
  tmp="$(mktemp -d)"
  trap 'rm -rf "$tmp"' EXIT
  for g in "${GEOS[@]}"; do
    mesh_one "$g.geo" "$tmp/$g.msh"
    if cmp -s "$g.msh" "$tmp/$g.msh"; then
      echo "generate.sh: $g.msh reproducible (byte-identical)" >&2
    else
      echo "generate.sh: ERROR: $g.msh differs between two runs" >&2
      exit 1
    fi
  done
fi

MSHS=()
for g in "${GEOS[@]}"; do MSHS+=("$g.msh"); done

# Plain table on stdout (also runs all the sanity checks; non-zero exit on failure).
"$PY" mesh_stats.py --interface 0.5 "${MSHS[@]}"

# Markdown table into README.md between the markers.
table="$("$PY" mesh_stats.py --markdown --interface 0.5 "${MSHS[@]}")"
readme="README.md"
begin="<!-- BEGIN MESH TABLE (written by generate.sh; do not edit by hand) -->"
end="<!-- END MESH TABLE -->"
block="$(printf '%s\n\nGenerated with gmsh %s, options `%s`.\n\n%s\n%s' "$begin" "$GMSH_VERSION" "${GMSH_OPTS[*]}" "$table" "$end")"
if [ -f "$readme" ] && grep -qF "$begin" "$readme"; then
  "$PY" - "$readme" "$begin" "$end" "$block" <<'PYEOF'
import sys
path, begin, end, block = sys.argv[1:5]
text = open(path).read()
i = text.index(begin)
j = text.index(end, i) + len(end)
open(path, "w").write(text[:i] + block + text[j:])
PYEOF
else
  printf '\n## Mesh statistics\n\n%s\n' "$block" >> "$readme"
fi
echo "generate.sh: table written to meshes/$readme" >&2
