// A box 0.2 x 0.05 x 0.04 m meshed with 4 x 2 x 2 structured hexahedra, like the built-in
// generator's `box: {size: [0.2, 0.05, 0.04], cells: [4, 2, 2]}` (tests/gmsh compares them).
// Meshes: see make-meshes.sh (order 1 and 2, ASCII and binary).
L = 0.2; W = 0.05; H = 0.04;
Point(1) = {0, 0, 0};
p[] = Extrude {L, 0, 0} { Point{1}; Layers{4}; };
s[] = Extrude {0, W, 0} { Line{p[1]}; Layers{2}; Recombine; };
v[] = Extrude {0, 0, H} { Surface{s[1]}; Layers{2}; Recombine; };
e = 1e-6;
Physical Volume("body") = {v[1]};
Physical Surface("clamp") = {Surface In BoundingBox{-e, -e, -e, e, W + e, H + e}};
Physical Surface("load") = {Surface In BoundingBox{L - e, -e, -e, L + e, W + e, H + e}};
Physical Surface("bottom") = {Surface In BoundingBox{-e, -e, -e, L + e, W + e, e}};
Physical Point("corner") = {Point In BoundingBox{L - e, W - e, H - e, L + e, W + e, H + e}};
