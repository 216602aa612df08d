#!/bin/sh
# Regenerate the README's renders: every scene (every .xml here) in both modes (hdr with the
# default clamp tone mapping, at the exposure a model's cases declare for its own scene:
# toon's hdr mode reflects the scan-line colours / 2π), and the course scene's hdr at
# 256 spp with aces.
#   sh scenes/renders/make.sh
set -e
cd "$(dirname "$0")"
for xml in ../*.xml; do
    scene=$(basename "$xml" .xml)
    for mode in scanline hdr; do
        [ "$scene/$mode" = "course/hdr" ] && continue
        exposure=0
        [ "$mode" = "hdr" ] && exposure=$(python -c "import sys; from mi_brdfs.bsdfs import cases
print(cases.ALL[sys.argv[1]].hdr_exposure if sys.argv[1] in cases.ALL else 0)" "$scene")
        mi-brdfs render "../$scene.xml" -D mode=$mode --exposure "$exposure" -o "${scene}_$mode.png" -q
    done
done
mi-brdfs render ../course.xml -D mode=hdr --spp 256 --tonemap aces -o course_hdr.png -q
