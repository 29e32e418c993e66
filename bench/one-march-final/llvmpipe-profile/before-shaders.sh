# Sourced by this folder's A/B scripts: the environment, the repository root as working folder,
# and $BEFORE, the shaders of 09e7f8f (the stop's start) extracted once.
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-root} VOLGRAPH_DATA=${VOLGRAPH_DATA:-../shared/data}
cd "$(dirname "${BASH_SOURCE[0]}")/../../.."
BEFORE=${BEFORE:-/tmp/volgraph-shaders-09e7f8f}
[ -d "$BEFORE" ] || { mkdir -p "$BEFORE" && git archive 09e7f8f shaders | tar -x -C "$BEFORE"; }
