#!/usr/bin/env bash
# Whether the editor's window answers while it works (not in CI). Opens `kiln edit SCENE`
# on a virtual screen, moves the pointer between two buttons of the material bar every
# second and takes a picture of them: "|" when the picture changed (the hover moved, so a
# frame was drawn), "=" when it did not (the window was frozen that second).
#
#   benches/editor/responsiveness.sh [KILN] [SCENE] [SECONDS]
#
# With COLD=1 Mesa's shader cache starts empty, as on a fresh machine, so every kernel
# compiles. Needs xvfb-run, xdotool and ImageMagick's `import`; the window is eframe's
# default 1280×800 at the top left of a 1600×1000 screen, the buttons at (31, 449) and
# (83, 449).
set -euo pipefail
KILN=${1:-target/release/kiln}
SCENE=${2:-assets/scenes/materials.kiln}
SECONDS_TO_WATCH=${3:-90}
OUT=$(mktemp -d)
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
if [ "${COLD:-0}" = 1 ]; then
    MESA_SHADER_CACHE_DIR=$(mktemp -d)
    export MESA_SHADER_CACHE_DIR
fi
XDG_STATE_HOME=$(mktemp -d) timeout $((SECONDS_TO_WATCH + 60)) \
    xvfb-run -s "-screen 0 1600x1000x24" bash -c "
        '$KILN' edit '$SCENE' 2>/dev/null &
        sleep 2
        for i in \$(seq 1 $SECONDS_TO_WATCH); do
            xdotool mousemove \$((31 + i % 2 * 52)) 449
            sleep 1
            import -window root -crop 200x30+0+435 $OUT/\$(printf %04d \$i).png
        done
        kill %1"
previous=""
for picture in "$OUT"/*.png; do
    hash=$(md5sum <"$picture" | cut -c1-8)
    if [ "$hash" = "$previous" ]; then printf '='; else printf '|'; fi
    previous=$hash
done
echo
rm -r "$OUT"
