#!/usr/bin/env bash
# Runs the whole test suite (after scripts/setup.sh has built), in stages, each
# with its wall time:
#   unit tests (ctest, Release build), then the hardening stages of
#   scripts/ci-hardening.sh: sanitizer build and tests, bounded fuzz runs, the
#   length-bound check.
# With arguments (ctest options, e.g. -R Rawlog) only the ctest stage runs;
# SHADYLOC_HARDENING=0 skips the hardening stages.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
t0=$(date +%s)
echo "=== [stage] unit tests (ctest)"
(cd "$here/build" && ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)" --timeout 600 "$@")
echo "=== [stage] unit tests: $(( $(date +%s) - t0 )) s"
if [ $# -eq 0 ] && [ "${SHADYLOC_HARDENING:-1}" != 0 ]; then
	bash "$here/scripts/ci-hardening.sh"
fi
echo "=== all stages: $(( $(date +%s) - t0 )) s"
