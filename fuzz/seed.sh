#!/usr/bin/env bash
# Builds the seed corpus fuzz/seeds/<target>/ from fixtures/ and tests/bad_inputs/ (small files
# only: libFuzzer runs with -max_len=8192). Run from the repository root after building scansurf
# (it converts a small mesh to every format through `scansurf fill-holes`).
set -euo pipefail
bin=${SCANSURF:-${CARGO_TARGET_DIR:-target}/release/scansurf}
s=fuzz/seeds
rm -rf "$s"; mkdir -p "$s"/{ply,obj,stl,xyz,adjacency}
# A small OBJ cut from the fixture: its first 150 faces, vertices renumbered.
awk '/^v /{v[++n]=$0; next} /^f / && nf<150 {nf++; line="f"; for(i=2;i<=4;i++){split($i,a,"/"); k=a[1]; if(!(k in m)){m[k]=++nm; order[nm]=k} line=line" "m[k]} f[nf]=line}
  END{for(i=1;i<=nm;i++) print v[order[i]]; for(i=1;i<=nf;i++) print f[i]}' fixtures/spot.obj > "$s/obj/spot_part.obj"
head -c 8192 fixtures/spot_tristrips_le.ply > "$s/ply/tristrips_le_head.ply"
head -c 8192 fixtures/spot_tristrips_be.ply > "$s/ply/tristrips_be_head.ply"
tmp=$(mktemp -d)
"$bin" fill-holes "$s/obj/spot_part.obj" -o "$tmp/a.ply" --ascii --quiet
"$bin" fill-holes "$s/obj/spot_part.obj" -o "$tmp/b.ply" --quiet
"$bin" fill-holes "$s/obj/spot_part.obj" -o "$tmp/a.stl" --ascii --quiet
"$bin" fill-holes "$s/obj/spot_part.obj" -o "$tmp/b.stl" --quiet
"$bin" fill-holes "$s/obj/spot_part.obj" -o "$tmp/a.xyz" --quiet
cp "$tmp/a.ply" "$s/ply/spot_part_ascii.ply"; cp "$tmp/b.ply" "$s/ply/spot_part_binary.ply"
cp "$tmp/a.stl" "$s/stl/spot_part_ascii.stl"; cp "$tmp/b.stl" "$s/stl/spot_part_binary.stl"
cp "$tmp/a.xyz" "$s/xyz/spot_part.xyz"
rm -rf "$tmp"
for ext in ply obj stl xyz; do
  for f in tests/bad_inputs/*."$ext"; do cp "$f" "$s/$ext/"; done
done
# Adjacency: byte strings that decode to a tetrahedron, a bow-tie and a non-manifold edge.
printf '\x03\x00\x02\x01\x00\x01\x03\x01\x02\x03\x00\x03\x02' > "$s/adjacency/tetra"
printf '\x04\x00\x01\x02\x00\x04\x03' > "$s/adjacency/bowtie"
printf '\x04\x00\x01\x02\x01\x00\x03\x00\x01\x04' > "$s/adjacency/nonmanifold_edge"
for t in ply obj stl xyz adjacency; do for f in "$s/$t"/*; do
  [ "$(stat -c %s "$f")" -le 8192 ] || head -c 8192 "$f" > "$f.tmp" && { [ -f "$f.tmp" ] && mv "$f.tmp" "$f" || true; }
done; done
du -sh "$s"; for t in ply obj stl xyz adjacency; do echo "$t: $(ls "$s/$t" | wc -l) files"; done
