#!/bin/sh
# Regenerate the README's renders: every scene (every .xml here) in both modes (hdr with the
# default clamp tone mapping), the course scene's hdr at 256 spp with aces, and
# toon's hdr at +2.65 EV (log2 2π: its hdr mode reflects the scan-line colours
# divided by 2π, so that it reflects at most its brightest colours).
#   sh scenes/renders/make.sh
set -e
cd "$(dirname "$0")"
for xml in ../*.xml; do
    scene=$(basename "$xml" .xml)
    for mode in scanline hdr; do
        [ "$scene/$mode" = "course/hdr" ] && continue
        exposure=0
        [ "$scene/$mode" = "toon/hdr" ] && exposure=2.65
        mi-brdfs render "../$scene.xml" -D mode=$mode --exposure $exposure -o "${scene}_$mode.png" -q
    done
done
mi-brdfs render ../course.xml -D mode=hdr --spp 256 --tonemap aces -o course_hdr.png -q
