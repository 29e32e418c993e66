#!/usr/bin/env bash
# A/B of the WINDOW define: the binary before (its shaders at HEAD) and after, alternating.
set -u
export XDG_RUNTIME_DIR=/tmp/xdg-root VOLGRAPH_DATA=/work/shared/data
cd /work/main
run() {
    if [ $1 = before ]; then b=/tmp/prewin/volgraph; s=(--shaders /tmp/prewin-shaders/shaders); else b=./target/release/volgraph; s=(); fi
    $b bench graphs --graphs graphs/kruger_westermann_2003/rc_b.ron,graphs/kruger_westermann_2003/rc.ron,graphs/modern/fastest.ron \
        --datasets hydrogen_atom,engine_vollib --tf sparse --size 512x512 --frames 8 --no-gpu-count --spp-size 0 --quiet "${s[@]}" \
        --json /tmp/abwin-$1-$2.json > /tmp/abwin-$1-$2.txt 2>&1
    echo "$(date +%T) $1 $2 exit $?"
}
run before 1; run after 1; run after 2; run before 2
