#!/usr/bin/env bash
# ctest fixture: the default dataset (scripts/make-default-dataset.sh) in
# DIR, rendered once and reused while DIR/.complete exists, for the tests
# that localise on it (tests/CMakeLists.txt, FIXTURES default_data). A
# checkout's own rawlogs/generated, when complete, is used by those tests
# instead (test::defaultDatasetDir); this renders only where it is absent.
#   tests/tools/default_dataset_fixture.sh DIR
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
dir="${1:?usage: default_dataset_fixture.sh DIR}"
complete=1
for t in evening_warm morning_low_sun noon overcast; do
  for f in "$here/rawlogs/generated/$t.rawlog" "$here/rawlogs/generated/$t.tum"; do [ -f "$f" ] || complete=0; done
done
if [ "$complete" = 1 ]; then
  echo "default_dataset_fixture: rawlogs/generated is complete: the tests read it"
  exit 0
fi
if [ -f "$dir/.complete" ]; then
  echo "default_dataset_fixture: $dir already rendered"
  exit 0
fi
rm -rf "$dir"
bash "$here/scripts/make-default-dataset.sh" "$dir" -q
touch "$dir/.complete"
