#!/usr/bin/env bash
# The main job on the built-in default data (after scripts/setup.sh has built):
# derive the monochrome and illumination-invariant channels of the sample
# rawlog, check them with stock MRPT tools, and write one invariant image.
# Output goes to build/demo/.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
app="$here/build/shadyloc"
out="$here/build/demo"
mkdir -p "$out"

echo "== shadyloc filter: monochrome + invariant channels =="
"$app" filter -i "$here/rawlogs/sample_stereo.rawlog" -o "$out/sample_filtered.rawlog" \
  -c "$here/config/filters.ini"

if command -v rawlog-edit >/dev/null; then
  echo "== stock rawlog-edit reads the result (plugin loaded) =="
  rawlog-edit -p "$here/build/libshadyloc_mrpt_plugin.so" -i "$out/sample_filtered.rawlog" --info \
    | grep -E "number of objects|sensor labels|Sensor"
fi
echo
echo "Done. Open the result with:  RawLogViewer -l $here/build/libshadyloc_mrpt_plugin.so $out/sample_filtered.rawlog"
