#!/usr/bin/env bash
# Regenerate the pictures in docs/images/ from the test corpus with infuse's own commands
# (infuse render, infuse gaze, infuse view --screenshot). Run after `make setup`:
#
#   docs/make_images.sh            # every picture
#   docs/make_images.sh quickstart # only those whose name starts with "quickstart"
#
# The corpus is found through INFUSE_CORPUS (default ../shared/corpus beside the repository).
# Pictures must stay under 300 KB each (tests/test_docs.py checks it).
set -euo pipefail
cd "$(dirname "$0")/.."
INFUSE=.venv/bin/infuse
CORPUS=${INFUSE_CORPUS:-../shared/corpus}
OUT=docs/images
ONLY=${1:-}
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

XBOT=$CORPUS/runxaway-models/Xbot.glb
AVATAR=$CORPUS/talkinghead/avatars/brunette-t.glb
ROBOT=$CORPUS/adibkn1-robot/RobotExpressive.glb
UTAH=$CORPUS/smartbody/behaviorsets/MaleLocomotion/skeletons/test_utah.sk
WALK=$CORPUS/bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_normal_001.bvh
WALK_FEMININE=$CORPUS/bandai/Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_feminine_001.bvh

want() { [ -z "$ONLY" ] || [[ "$1" == "$ONLY"* ]]; }

if want quickstart-walk; then  # index.md, quickstart.md
  "$INFUSE" retarget "$WALK" --to "$XBOT" -o "$WORK/xbot_walk.glb"
  "$INFUSE" render "$WORK/xbot_walk.glb" -o "$OUT/quickstart-walk.png" --strip 6
fi

if want render-mesh; then  # render.md
  "$INFUSE" retarget "$WALK" --to "$AVATAR" -o "$WORK/avatar_walk.glb"
  "$INFUSE" retarget "$WALK" --to "$XBOT" -o "$WORK/xbot_walk.glb"
  "$INFUSE" render "$WORK/avatar_walk.glb" "$WORK/xbot_walk.glb" --clip dataset-1_walk_normal_001 \
      -o "$OUT/render-mesh.png" --frame 40 --size 800x420 --title ""
fi

if want quickstart-view; then  # quickstart.md
  "$INFUSE" speak "$AVATAR" "Hello, I am infused." -o "$WORK/hello.glb"
  "$INFUSE" view "$WORK/hello.glb" --screenshot "$OUT/quickstart-view.png" --time 0.6 --size 900x560
fi

if want retargeting; then  # retargeting.md
  "$INFUSE" retarget "$WALK_FEMININE" --to "$XBOT" -o "$WORK/xbot.bvh"
  "$INFUSE" retarget "$WALK_FEMININE" --to "$UTAH" -o "$WORK/utah.bvh"
  cp "$WALK_FEMININE" "$WORK/bandai_walk.bvh"
  "$INFUSE" render "$WORK/bandai_walk.bvh" "$WORK/xbot.bvh" "$WORK/utah.bvh" -o "$OUT/retargeting.png" \
      --frame 52 --size 960x400 --title ""
fi

if want gaze; then  # controllers.md
  "$INFUSE" gaze "$AVATAR" -o "$OUT/gaze.png" --strip 5 --saccades talk --blink --breathing
fi

if want viewer; then  # viewer.md
  "$INFUSE" view "$ROBOT" --targets "$OUT/viewer-robot.targets.json" --screenshot "$OUT/viewer.png" \
      --clip Wave --time 0.9 --size 1000x680
fi

if want walk_path; then  # packs.md
  .venv/bin/python tools/walk_path.py "$XBOT" -o "$OUT/walk_path.png" --pack locomotion-female
fi

if want scene; then  # scenes.md
  INFUSE_CORPUS=$(cd "$CORPUS" && pwd) "$INFUSE" run examples/scenes/demo.toml -o "$WORK/scene" --strip 6 --quiet
  cp "$WORK/scene/preview.png" "$OUT/scene.png"
fi

if want gestures; then  # bml.md, packs.md
  INFUSE_CORPUS=$(cd "$CORPUS" && pwd) "$INFUSE" run examples/scenes/gestures.toml -o "$WORK/gestures" --strip 6 --quiet
  cp "$WORK/gestures/preview.png" "$OUT/gestures.png"
fi

if want pointing; then  # bml.md
  INFUSE_CORPUS=$(cd "$CORPUS" && pwd) "$INFUSE" run examples/scenes/pointing.toml -o "$WORK/pointing" --strip 6 --quiet
  cp "$WORK/pointing/preview.png" "$OUT/pointing.png"
fi

if want nonverbal; then  # nonverbal.md
  INFUSE_CORPUS=$(cd "$CORPUS" && pwd) "$INFUSE" run examples/scenes/conversation.toml -o "$WORK/conversation" --strip 6 --quiet
  cp "$WORK/conversation/preview.png" "$OUT/nonverbal.png"
fi

for png in "$OUT"/*.png; do
  size=$(stat -c %s "$png")
  [ "$size" -lt 307200 ] || { echo "make_images: $png is $size bytes, over 300 KB" >&2; exit 1; }
done
echo "make_images: done"
