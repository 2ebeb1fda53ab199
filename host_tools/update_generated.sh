#!/bin/sh
# Regenerate the host package's copies of the protocol artefacts from protocol/,
# and the command index docs/handlers.md.
# Run after every change of protocol/landscape.proto, .dbc or .options, of the
# robot model (firmware/model/ls_robot_model.c, the URDF's source), of the
# model file's keys (firmware/model/ls_robot_model_file.c) or of a handler;
# tests/host/test_generated.py fails while the committed copies are stale.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/.." && pwd)
out="$here/src/landscape/_generated"
protoc -I"$root/protocol" -I/usr/include --python_out="$out" --pyi_out="$out" \
  --descriptor_set_out="$out/landscape.desc" "$root/protocol/landscape.proto"
cp "$root/protocol/landscape.dbc" "$out/landscape.dbc"
cp "$root/protocol/landscape.options" "$out/landscape.options"
# The arm's URDF, printed by the built ls_urdf from firmware/model/ls_robot_model.c.
ls_urdf="${LS_BUILD_DIR:-$root/build}/bin/ls_urdf"
[ -x "$ls_urdf" ] || { echo "update_generated.sh: $ls_urdf is missing: build first (bash .ci/build)" >&2; exit 1; }
"$ls_urdf" -o "$out/ls-sim6.urdf"
# The robot model file's keys, units and ranges (`landscape model check`).
"${LS_BUILD_DIR:-$root/build}/bin/ls_robot_model" keys > "$out/robot-model-keys.json"
# The command index: each command's handler, file and final notices.
/usr/bin/python3 "$root/protocol/gen_registry.py" --index "$out" "$root/firmware/core" "$root/docs/handlers.md"
echo "updated $out/landscape_pb2.py(i), landscape.desc, landscape.dbc, landscape.options, ls-sim6.urdf,"\
  "robot-model-keys.json and docs/handlers.md"
