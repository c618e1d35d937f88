// The box 0.2 x 0.05 x 0.04 m of box-hex.geo meshed with unstructured tetrahedra.
SetFactory("OpenCASCADE");
L = 0.2; W = 0.05; H = 0.04;
Box(1) = {0, 0, 0, L, W, H};
Mesh.MeshSizeMax = 0.02;
e = 1e-6;
Physical Volume("body") = {1};
Physical Surface("clamp") = {Surface In BoundingBox{-e, -e, -e, e, W + e, H + e}};
Physical Surface("load") = {Surface In BoundingBox{L - e, -e, -e, L + e, W + e, H + e}};
