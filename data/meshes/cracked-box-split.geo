// cracked-box-hex.geo, meshed and split by Gmsh's Crack plugin: the crack's nodes are duplicated
// (open on the faces y = 0 and y = W), the elements above it use the copies, and the physical
// surface "crack" holds both sides. crackle recognises the coincident faces.
// Run with: gmsh cracked-box-split.geo -parse_and_exit (writes cracked-box-split.msh).
Include "cracked-box-hex.geo";
Mesh 3;
Plugin(Crack).Dimension = 2;
Plugin(Crack).PhysicalGroup = 10;
Plugin(Crack).OpenBoundaryPhysicalGroup = 11;
Plugin(Crack).Run;
Mesh.MshFileVersion = 4.1;
Save "cracked-box-split.msh";
