// One hexahedron (the unit cube): the base of the bad files in bad/ (see make-meshes.sh).
Point(1) = {0, 0, 0};
p[] = Extrude {1, 0, 0} { Point{1}; Layers{1}; };
s[] = Extrude {0, 1, 0} { Line{p[1]}; Layers{1}; Recombine; };
v[] = Extrude {0, 0, 1} { Surface{s[1]}; Layers{1}; Recombine; };
Physical Volume("body") = {v[1]};
