#!/usr/bin/env bash
# Regenerates the mesh files of this folder from their .geo files with Gmsh 4.8 (apt-get install gmsh).
# The tests read the .msh files; they never run Gmsh.
set -euo pipefail
cd "$(dirname "$0")"
mesh() { gmsh "$@" -format msh41 -v 1; }
mesh -3 box-hex.geo -o box-hex8.msh
mesh -3 -order 2 box-hex.geo -o box-hex27.msh
mesh -3 -order 2 -bin box-hex.geo -o box-hex27-binary.msh
mesh -3 -order 2 cracked-box-hex.geo -o cracked-box-hex27.msh
gmsh cracked-box-split.geo -parse_and_exit -v 1
mesh -3 box-tet.geo -o box-tet4.msh
mesh -3 -order 2 box-tet.geo -o box-tet10.msh
mesh -3 cracked-box-tet.geo -o cracked-box-tet4.msh
mesh -3 -order 2 cracked-box-tet.geo -o cracked-box-tet10.msh

# Files crackle must reject (tests/gmsh checks each message).
mkdir -p bad
mesh -3 prism.geo -o bad/prism.msh
gmsh -3 one-hex.geo -format msh22 -v 1 -o bad/version-2.2.msh
mesh -3 one-hex.geo -o bad/one-hex.msh
# Truncated in the middle of $Nodes.
head -n "$(( $(grep -n '^\$Nodes' bad/one-hex.msh | cut -d: -f1) + 6 ))" bad/one-hex.msh > bad/truncated.msh
# The same hexahedron with two nodes of its bottom face swapped: inverted corners.
awk 'f && NF == 9 { t = $3; $3 = $4; $4 = t } /^\$Elements/ { f = 1 } /^\$EndElements/ { f = 0 } { print }' \
  bad/one-hex.msh > bad/inverted.msh
rm bad/one-hex.msh
