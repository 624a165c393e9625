#!/usr/bin/env bash
# The project's test command (README "Run the tests"): installs lavapipe if no Vulkan
# driver exists, then runs every test, kernel tests included, on the selected adapter.
set -euo pipefail
cd "$(dirname "$0")/.."
source ci/lavapipe.sh
cargo run --quiet -- info
cargo test --no-fail-fast "$@"
