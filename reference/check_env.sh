#!/usr/bin/env bash
# Exit 0 if Debian's /usr/bin/python3 can import dolfinx 0.5.x and gmsh (the
# environment reference/solve.py needs); otherwise say what to install and exit 1.
set -u
PY=/usr/bin/python3
hint() {
  cat >&2 <<'MSG'
check_env.sh: install the Debian packages (as root, or with sudo):
    apt-get update && apt-get install -y gmsh python3-gmsh python3-dolfinx
and run the reference solver with /usr/bin/python3 (not a pyenv/venv python3).
MSG
}
if [ ! -x "$PY" ]; then
  echo "check_env.sh: $PY not found" >&2; hint; exit 1
fi
if ! out="$("$PY" -c 'import dolfinx, gmsh; print(dolfinx.__version__)' 2>&1)"; then
  echo "check_env.sh: '$PY -c \"import dolfinx, gmsh\"' failed:" >&2
  echo "$out" | tail -n 3 >&2
  hint; exit 1
fi
ver="$(echo "$out" | tail -n 1)"
case "$ver" in
  0.5.*) echo "check_env.sh: OK (dolfinx $ver, gmsh python module, $PY)"; exit 0 ;;
  *) echo "check_env.sh: dolfinx $ver found, but reference/solve.py is written for dolfinx 0.5.x" >&2
     hint; exit 1 ;;
esac
