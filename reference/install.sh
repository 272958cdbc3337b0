#!/usr/bin/env bash
# Installs what the dolfinx reference solves need (Debian packages python3-dolfinx, gmsh,
# python3-gmsh), unless /usr/bin/python3 can already import dolfinx 0.5 and gmsh.
set -euo pipefail
if /usr/bin/python3 -c "import dolfinx, gmsh; assert dolfinx.__version__.startswith('0.5')" 2>/dev/null; then
  exit 0
fi
SUDO=""
if [ "$(id -u)" != 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO=sudo; else
    echo "reference/install.sh: need root or sudo to apt-get install python3-dolfinx gmsh python3-gmsh" >&2
    exit 1
  fi
fi
if ! command -v apt-get >/dev/null 2>&1; then
  echo "reference/install.sh: apt-get not found; install dolfinx 0.5.x for /usr/bin/python3 by hand" >&2
  exit 1
fi
echo "installing python3-dolfinx, gmsh, python3-gmsh with apt-get ..." >&2
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq python3-dolfinx gmsh python3-gmsh >/dev/null
/usr/bin/python3 -c "import dolfinx, gmsh; print('dolfinx', dolfinx.__version__)" >&2
