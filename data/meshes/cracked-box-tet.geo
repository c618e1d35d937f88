// The box of box-tet.geo with the crack of cracked-box-hex.geo (z = 0.02, x in [0.05, 0.1],
// through the width) as an embedded surface "crack" of unstructured tetrahedra.
SetFactory("OpenCASCADE");
L = 0.2; W = 0.05; H = 0.04;
Box(1) = {0, 0, 0, L, W, H};
Rectangle(10) = {0.05, 0, H / 2, 0.05, W};
BooleanFragments{ Volume{1}; Delete; }{ Surface{10}; Delete; }
Mesh.MeshSizeMax = 0.02;
e = 1e-6;
Physical Volume("body") = {Volume{:}};
Physical Surface("clamp") = {Surface In BoundingBox{-e, -e, -e, e, W + e, H + e}};
Physical Surface("crack") = {Surface In BoundingBox{0.05 - e, -e, H / 2 - e, 0.1 + e, W + e, H / 2 + e}};
