// A unit cube of 6-node prisms (an element type crackle does not read): bad/prism.msh.
Point(1) = {0, 0, 0};
p[] = Extrude {1, 0, 0} { Point{1}; Layers{1}; };
s[] = Extrude {0, 1, 0} { Line{p[1]}; Layers{1}; };
v[] = Extrude {0, 0, 1} { Surface{s[1]}; Layers{1}; Recombine; };
Physical Volume("body") = {v[1]};
