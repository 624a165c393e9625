#!/usr/bin/env bash
# Makes sure a Vulkan driver is present; on a machine without one, installs Mesa's CPU
# driver (lavapipe). Source it: it exports the variables that select lavapipe when no
# other adapter has been asked for.
SUDO=""
[ "$(id -u)" = 0 ] || SUDO="sudo"
if ! ls /usr/share/vulkan/icd.d/*.json >/dev/null 2>&1; then
    echo "ci/lavapipe.sh: no Vulkan driver found; installing mesa-vulkan-drivers (lavapipe)" >&2
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
# Opt-in, Debian 12 only: RENDERNET_MESA=25 selects Mesa 25 from bookworm-backports (the
# tiny network 1.0-1.4x faster than Mesa 22.3.6 on an AMD Zen 3, README "Benchmarks"),
# extracted into a cache folder and chosen with VK_DRIVER_FILES; the system driver stays as
# it is. CI uses the system driver.
if [ "${RENDERNET_MESA:-}" = 25 ]; then
    mesa_dir="${XDG_CACHE_HOME:-$HOME/.cache}/rendernet/mesa25"
    if [ ! -f "$mesa_dir/lvp.json" ]; then
        echo "ci/lavapipe.sh: fetching Mesa 25 (mesa-vulkan-drivers from bookworm-backports) into $mesa_dir" >&2
        (
            set -e
            mkdir -p "$mesa_dir"
            # The suite is added beside the machine's own mirror (first URIs line), never a written host.
            uri=$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources)
            printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' "$uri" \
                | $SUDO tee /etc/apt/sources.list.d/rendernet-backports.sources >/dev/null
            $SUDO apt-get update -qq >/dev/null
            cd "$mesa_dir"
            apt-get download -qq mesa-vulkan-drivers/bookworm-backports >/dev/null 2>&1
            dpkg-deb -x mesa-vulkan-drivers_*.deb extracted
            lib=$(find "$mesa_dir/extracted" -name libvulkan_lvp.so | head -n 1)
            [ -n "$lib" ]
            printf '{"file_format_version":"1.0.0","ICD":{"library_path":"%s","api_version":"1.3.0"}}\n' "$lib" > "$mesa_dir/lvp.json"
        ) || echo "ci/lavapipe.sh: could not fetch Mesa 25; keeping the system driver" >&2
    fi
    [ -f "$mesa_dir/lvp.json" ] && export VK_DRIVER_FILES="$mesa_dir/lvp.json"
fi
