#!/usr/bin/env bash
# Create or update a peer's virtual environment from its pinned requirements:
#
#   benchmarks/peers/setup_env.sh PEER [ROOT]     # -> ROOT/PEER (default ROOT: .venv-peers)
#
# PEER is a name with benchmarks/peers/requirements-PEER.txt (crocoddyl, drake, opensim). The
# env is made with ${PYTHON:-python3.11} -m venv and pip-installs that file; a stamp (the
# file's hash) skips the install when nothing changed. Exits 1 with one line on stderr saying why when the env
# cannot be made (no such peer, no Python 3.11, a package pip cannot install): `make
# bench-peers` then skips that peer with the reason.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
peer="${1:?usage: setup_env.sh PEER [ROOT]}"
root="${2:-$repo/.venv-peers}"
requirements="$repo/benchmarks/peers/requirements-$peer.txt"
venv="$root/$peer"
stamp="$venv/.requirements.sha256"
python_bin="${PYTHON:-python3.11}"

die() { printf 'setup_env %s: %s\n' "$peer" "$*" >&2; exit 1; }

[[ -f "$requirements" ]] || die "no $requirements"
hash="$(sha256sum "$requirements" | cut -d' ' -f1)"
if [[ -x "$venv/bin/python" && -f "$stamp" && "$(cat "$stamp")" == "$hash" ]]; then
  exit 0
fi
command -v "$python_bin" >/dev/null 2>&1 || die "$python_bin is missing"
if [[ ! -x "$venv/bin/python" ]]; then
  "$python_bin" -m venv "$venv" || die "$python_bin -m venv $venv failed"
fi
log="$venv/pip-install.log"
if ! "$venv/bin/python" -m pip install --disable-pip-version-check -r "$requirements" \
    >"$log" 2>&1; then
  die "pip could not install $requirements: $(grep -m1 -E '^ERROR' "$log" || tail -n1 "$log")"
fi
echo "$hash" >"$stamp"
printf 'setup_env %s: %s ready\n' "$peer" "$venv"
