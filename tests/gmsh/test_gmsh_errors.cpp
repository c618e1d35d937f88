// Files and groups crackle must reject, each with a message naming the file (issue 7).
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/errors.hpp"
#include "gmsh_testing.hpp"
#include "mesh/gmsh.hpp"

namespace crackle::mesh {
namespace {

using testing::mesh_file;

std::string error_of(const std::string& file, const std::string& crack_group = "") {
  try {
    GmshOptions options;
    options.crack_group = crack_group;
    read_gmsh(file, options);
  } catch (const InputError& error) {
    return error.what();
  }
  return "no error";
}

std::string parse_error(const std::string& contents) {
  try {
    parse_gmsh(contents, "part.msh");
  } catch (const InputError& error) {
    return error.what();
  }
  return "no error";
}

std::string contents_of(const std::string& file) {
  std::ifstream stream(file, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

TEST(GmshErrors, BadFilesAreNamed) {
  const std::string bad = mesh_file("bad/");
  EXPECT_EQ(error_of(bad + "prism.msh"),
            bad + "prism.msh: unsupported element type 6 (6-node prism) in volume 1; crackle reads 4- and 10-node "
                  "tetrahedra and 8- and 27-node hexahedra");
  EXPECT_EQ(error_of(bad + "version-2.2.msh"),
            bad + "version-2.2.msh: expected a Gmsh MSH 4.1 file, got version 2.2 (save it with gmsh -format msh41, "
                  "or Mesh.MshFileVersion = 4.1)");
  EXPECT_EQ(error_of(bad + "truncated.msh"),
            bad + "truncated.msh: truncated file: $Nodes ends before its 9 node blocks");
  EXPECT_EQ(error_of(bad + "inverted.msh"),
            bad + "inverted.msh: element 1 (8-node hexahedron) is inverted or degenerate: scaled Jacobian -0.353553390593274 "
                  "at a corner (its nodes must follow Gmsh's order with a positive volume)");
  EXPECT_EQ(error_of(bad + "missing.msh"),
            bad + "missing.msh: expected a readable Gmsh mesh file, got No such file or directory");
}

TEST(GmshErrors, TruncatedAndForeignContents) {
  const std::string ascii = contents_of(mesh_file("box-hex8.msh"));
  const std::string binary = contents_of(mesh_file("box-hex27-binary.msh"));
  EXPECT_EQ(parse_error(""), "part.msh: expected a Gmsh MSH 4.1 file, got an empty file");
  EXPECT_EQ(parse_error("solid cube\nfacet normal 0 0 1\n"),
            "part.msh: expected a Gmsh MSH 4.1 file (starting with $MeshFormat), got 'solid cube'");
  EXPECT_EQ(parse_error("$MeshFormat\n4 0 8\n$EndMeshFormat\n"),
            "part.msh: expected a Gmsh MSH 4.1 file, got version 4 (save it with gmsh -format msh41, or "
            "Mesh.MshFileVersion = 4.1)");
  // Cut anywhere, a file is reported as truncated, never read past its end.
  for (const std::string* whole : {&ascii, &binary}) {
    for (std::size_t cut = whole->size() / 7; cut < whole->size() - 20; cut += whole->size() / 7) {
      const std::string message = parse_error(whole->substr(0, cut));
      EXPECT_EQ(message.rfind("part.msh: truncated file: $", 0), 0u) << message;
    }
  }
  // A count the rest of the file cannot hold is a truncated file, not a huge allocation.
  std::string huge = ascii;
  const std::size_t nodes = huge.find("$Nodes\n") + 7;
  huge.replace(nodes, huge.find('\n', nodes) - nodes, "1 99999999999999 1 99999999999999");
  EXPECT_EQ(parse_error(huge), "part.msh: truncated file: $Nodes ends before its 99999999999999 nodes");
  EXPECT_EQ(parse_error(ascii.substr(0, ascii.find("$Elements"))),
            "part.msh: truncated file: the file ends before an $Elements section");
  std::string garbled = ascii;
  garbled.replace(garbled.find("\n$EndNodes") - 4, 4, "0.0z");
  EXPECT_EQ(parse_error(garbled), "part.msh: $Nodes: expected a node coordinate, got '0.0z'");
}

TEST(GmshErrors, GroupsThatAreNotCracks) {
  const std::string file = mesh_file("box-hex8.msh");
  EXPECT_EQ(error_of(file, "crak"),
            file + ": crack: no physical group 'crak' (the file has: body, bottom, clamp, corner, load)");
  EXPECT_EQ(error_of(file, "body"), file + ": crack group 'body' is a physical volume, not a surface of the mesh");
  EXPECT_EQ(error_of(file, "corner"), file + ": crack group 'corner' is a physical point, not a surface of the mesh");
  EXPECT_EQ(error_of(file, "clamp"),
            file + ": crack group 'clamp' is not a surface inside the mesh: its face with corners (0, 0, 0), "
                   "(0, 0, 0.02), (0, 0.025, 0.02), ... lies on the outer boundary of the body");
}

}  // namespace
}  // namespace crackle::mesh
