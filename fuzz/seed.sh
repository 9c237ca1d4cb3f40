#!/usr/bin/env bash
# Fills corpus/<target>/ with the seed inputs of each fuzz target: Kiln's bundled scenes
# and materials, the OBJ importer's fixtures, and the Khronos glTF-Validator's valid and
# broken files from ../shared/corpus (docs/RELIABILITY.md says how to run the targets).
set -euo pipefail
cd "$(dirname "$0")"
root=..
shared=../../shared/corpus

seed() {
    local target=$1
    shift
    mkdir -p "corpus/$target"
    for file in "$@"; do
        # Named by content, as libFuzzer names what it adds, so reseeding adds nothing twice.
        cp "$file" "corpus/$target/$(sha1sum "$file" | cut -c1-40)"
    done
    echo "$target: $# seed files"
}

shopt -s nullglob globstar
seed scene "$root"/assets/scenes/*.kiln
seed material "$root"/assets/materials/*.kmat
# The OBJ target's inputs carry the MTL library after a line `#mtl` (fuzz/src/lib.rs).
fixtures="$root"/plugins/obj/tests/fixtures
mkdir -p corpus/obj-joined
for obj in "$fixtures"/*.obj; do
    joined="corpus/obj-joined/$(basename "$obj")"
    sed 's/^mtllib .*/mtllib input.mtl/' "$obj" >"$joined"
    printf '\n#mtl\n' >>"$joined"
    cat "$fixtures/scene.mtl" >>"$joined"
done
seed obj corpus/obj-joined/*.obj seeds/obj/*.obj
rm -r corpus/obj-joined
if [ -d "$shared/gltf-validator" ]; then
    seed gltf "$shared"/gltf-validator/**/*.gltf "$shared"/gltf-validator/**/*.glb
else
    echo "no $shared/gltf-validator: the gltf target starts from nothing" >&2
    mkdir -p corpus/gltf
fi
