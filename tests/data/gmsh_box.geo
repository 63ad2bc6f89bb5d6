SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 1, 1};
Mesh.MeshSizeMax = 2;
Physical Surface("skin") = {1, 2, 3, 4, 5, 6};
Physical Volume("solid") = {1};
