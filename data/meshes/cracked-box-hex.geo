// A box 0.2 x 0.05 x 0.04 m meshed with 8 x 2 x 2 structured hexahedra with a crack normal to z at
// z = 0.02 over x in [0.05, 0.1], through the width (y in [0, 0.05]): the built-in generator's
// `crack: {plane: {normal: z, at: 0.02}, region: {x: [0.05, 0.1], y: [0, 0.05]}}`.
// The crack is the physical surface "crack" (an interior surface, split by crackle).
L = 0.2; W = 0.05; H = 0.04;
Point(1) = {0, 0, 0};
a[] = Extrude {0.05, 0, 0} { Point{1}; Layers{2}; };
b[] = Extrude {0.05, 0, 0} { Point{a[0]}; Layers{2}; };
c[] = Extrude {0.1, 0, 0} { Point{b[0]}; Layers{4}; };
lines[] = {a[1], b[1], c[1]};
volumes[] = {};
For i In {0 : 2}
  base[] = Extrude {0, W, 0} { Line{lines[i]}; Layers{2}; Recombine; };
  low[] = Extrude {0, 0, H / 2} { Surface{base[1]}; Layers{1}; Recombine; };
  high[] = Extrude {0, 0, H / 2} { Surface{low[0]}; Layers{1}; Recombine; };
  volumes[] += {low[1], high[1]};
EndFor
Coherence;
e = 1e-6;
Physical Volume("body") = {volumes[]};
Physical Surface("clamp") = {Surface In BoundingBox{-e, -e, -e, e, W + e, H + e}};
Physical Surface("crack", 10) = {Surface In BoundingBox{0.05 - e, -e, H / 2 - e, 0.1 + e, W + e, H / 2 + e}};
// The crack's edges on the faces y = 0 and y = W open (for Gmsh's Crack plugin, cracked-box-split.geo).
Physical Curve("crack-open", 11) = {Curve In BoundingBox{0.05 - e, -e, H / 2 - e, 0.1 + e, e, H / 2 + e},
                                    Curve In BoundingBox{0.05 - e, W - e, H / 2 - e, 0.1 + e, W + e, H / 2 + e}};
