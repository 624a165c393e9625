#!/usr/bin/env bash
# Makes sure a Vulkan driver is present; on a machine without one, installs Mesa's CPU
# driver (lavapipe). Source it: it exports the variables that select lavapipe when no
# other adapter has been asked for.
if ! ls /usr/share/vulkan/icd.d/*.json >/dev/null 2>&1; then
    echo "ci/lavapipe.sh: no Vulkan driver found; installing mesa-vulkan-drivers (lavapipe)" >&2
    SUDO=""
    [ "$(id -u)" = 0 ] || SUDO="sudo"
    export DEBIAN_FRONTEND=noninteractive
    $SUDO apt-get update -qq >/dev/null
    $SUDO apt-get install -y -qq mesa-vulkan-drivers >/dev/null
fi
if [ -z "${WGPU_BACKEND:-}${WGPU_ADAPTER_NAME:-}" ] && ! ls /dev/dri/renderD* /dev/nvidia0 >/dev/null 2>&1; then
    # No GPU device node: select lavapipe explicitly, as wgpu's own CI does.
    export WGPU_BACKEND=vulkan WGPU_ADAPTER_NAME=llvmpipe
fi
# Mesa warns when this is unset; any writable folder silences it.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    export XDG_RUNTIME_DIR="${TMPDIR:-/tmp}/rendernet-xdg-$(id -u)"
    mkdir -p "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
fi
