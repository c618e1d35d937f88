// Scene keys of issue 7: `mesh: {gmsh: ...}`, groups in `boundary` and `crack`, `materials` regions.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/errors.hpp"
#include "gmsh_testing.hpp"
#include "pipeline/model.hpp"
#include "scene/scene.hpp"

namespace crackle {
namespace {

/// A scratch folder holding copies of the meshes of data/meshes (mesh paths in a scene are relative
/// to the scene file).
std::string scratch(const std::string& name) {
  static const std::filesystem::path folder = [] {
    // One folder per process: ctest runs the tests of this file in parallel processes.
    const std::filesystem::path path =
        std::filesystem::path(::testing::TempDir()) / ("gmsh_scene_" + std::to_string(getpid()));
    std::filesystem::create_directories(path);
    for (const char* mesh : {"box-hex8.msh", "box-tet4.msh", "cracked-box-hex27.msh"}) {
      std::filesystem::copy_file(testing::mesh_file(mesh), path / mesh,
                                 std::filesystem::copy_options::overwrite_existing);
    }
    return path;
  }();
  return (folder / name).string();
}

std::string write_scene(const std::string& name, const std::string& text) {
  const std::string path = scratch(name);
  std::ofstream(path) << text;
  return path;
}

std::string build_error(const std::string& path) {
  try {
    pipeline::build_model(scene::load_scene(path));
  } catch (const InputError& error) {
    return error.what();
  }
  return "no error";
}

const std::string kMaterial = "material: {E: 210.0e9, nu: 0.3, rho: 7850.0}\n";

TEST(GmshScene, MeshFileGroupsAndCrack) {
  const std::string path = write_scene("test-scene-gmsh.yaml",
                                       "mesh: {gmsh: cracked-box-hex27.msh}\n" + kMaterial +
                                           "boundary:\n  - {group: clamp, fix: [x, y, z]}\n"
                                           "crack: {group: crack, gap: 1.0e-6}\n");
  const scene::Scene scene = scene::load_scene(path);
  EXPECT_EQ(scene.gmsh_file, scratch("cracked-box-hex27.msh"));
  ASSERT_TRUE(scene.crack_group);
  EXPECT_EQ(scene.crack_group->group, "crack");
  EXPECT_EQ(scene.crack_group->gap, 1.0e-6);
  EXPECT_TRUE(scene.has_crack());
  EXPECT_FALSE(scene.crack);
  EXPECT_EQ(scene.modal.variants, (std::vector<mesh::Variant>{mesh::Variant::uncracked, mesh::Variant::open}));
  const pipeline::Model model = pipeline::build_model(scene);
  EXPECT_TRUE(model.mesh.has_crack());
  ASSERT_EQ(model.dirichlet.size(), 1u);
  EXPECT_EQ(model.dirichlet[0].nodes, model.mesh.node_sets.at("clamp"));
  EXPECT_EQ(model.dirichlet[0].source, path + ":4: boundary[0] (group clamp)");
  std::filesystem::remove(path);
}

TEST(GmshScene, MaterialRegionsFromVolumeGroups) {
  const std::string path = write_scene(
      "test-scene-regions.yaml",
      "mesh: {gmsh: box-tet4.msh}\n"
      "materials:\n"
      "  - {name: core, isotropic: {E: 70e9, nu: 0.33}, rho: 2700, region: {group: body}}\n");
  const pipeline::Model model = pipeline::build_model(scene::load_scene(path));
  EXPECT_EQ(model.materials.size(), 1u);
  write_scene("test-scene-regions.yaml",
              "mesh: {gmsh: box-tet4.msh}\n"
              "materials:\n"
              "  - {name: core, isotropic: {E: 70e9, nu: 0.33}, rho: 2700, region: {group: skin}}\n");
  EXPECT_EQ(build_error(path), path + ":3: materials[0].region.group: expected a volume group of the mesh (body), got 'skin'");
  std::filesystem::remove(path);
}

TEST(GmshScene, MissingGroupsAndWrongCombinations) {
  const std::string path = write_scene("test-scene-bad.yaml", "mesh: {gmsh: box-hex8.msh}\n" + kMaterial +
                                                                   "boundary:\n  - {group: clmap, fix: [x]}\n");
  EXPECT_EQ(build_error(path), path + ":4: boundary[0].group: expected a group of the mesh (body, bottom, clamp, "
                                      "corner, load), got 'clmap'");
  write_scene("test-scene-bad.yaml", "mesh: {gmsh: box-hex8.msh}\n" + kMaterial + "crack: {group: crak}\n");
  EXPECT_EQ(build_error(path), path + ": mesh.gmsh: " + scratch("box-hex8.msh") +
                                   ": crack: no physical group 'crak' (the file has: body, bottom, clamp, corner, load)");
  write_scene("test-scene-bad.yaml", "mesh: {gmsh: box-hex8.msh}\n" + kMaterial +
                                         "transient:\n  excitation: {group: lod, direction: z, amplitude: 1.0, "
                                         "frequency: 100.0}\n  duration: 0.01\n");
  EXPECT_EQ(build_error(path), path + ": transient.excitation.group: expected a group of the mesh (body, bottom, "
                                      "clamp, corner, load), got 'lod'");
  write_scene("test-scene-bad.yaml", "mesh: {gmsh: nothing.msh}\n" + kMaterial);
  EXPECT_EQ(build_error(path), path + ": mesh.gmsh: " + scratch("nothing.msh") +
                                   ": expected a readable Gmsh mesh file, got No such file or directory");
  std::filesystem::remove(path);

  auto parse_error = [](const std::string& text) {
    try {
      scene::parse_scene(text, "part.yaml");
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  const std::string box = "mesh:\n  box: {size: [0.2, 0.02, 0.01], cells: [4, 2, 2], order: 1}\n";
  EXPECT_EQ(parse_error("mesh: {gmsh: part.msh}\n" + kMaterial + "boundary:\n  - {fix: [x]}\n"),
            "part.yaml:4: boundary[0]: expected face (a box face) or group (a group of the mesh), got neither");
  EXPECT_EQ(parse_error(box + kMaterial + "boundary:\n  - {face: x-, group: clamp, fix: [x]}\n"),
            "part.yaml:5: boundary[0]: expected face (a box face) or group (a group of the mesh), got both");
  EXPECT_EQ(parse_error(box + kMaterial + "crack: {group: crack}\n"),
            "part.yaml:4: crack.group: expected plane and region (a box mesh has no groups; group needs mesh.gmsh), "
            "got 'crack'");
  EXPECT_EQ(parse_error("mesh: {gmsh: part.msh}\n" + kMaterial +
                        "crack:\n  plane: {normal: z, at: 0.005}\n  region: {x: [0, 0.1], y: [0, 0.02]}\n"),
            "part.yaml:3: crack: expected group (the physical surface of the crack in the Gmsh mesh), got plane and "
            "region");
  EXPECT_EQ(parse_error(box + kMaterial + "materials:\n  - {name: a, isotropic: {E: 1e9, nu: 0.3}, rho: 1}\n"),
            "part.yaml:4: materials: expected either material (one for the whole body) or materials, got both");
  EXPECT_EQ(parse_error(box + "materials:\n  - {name: a, rho: 1}\n"),
            "part.yaml:4: materials[0]: expected isotropic or orthotropic constants, got neither");
  EXPECT_EQ(parse_error(box + "materials:\n  - {name: a, isotropic: {E: 1e9, nu: 0.3}, rho: 1, region: {group: g}}\n"),
            "part.yaml:4: materials[0].region.group: expected coordinate ranges x, y, z (a box mesh has no groups), "
            "got 'g'");
  EXPECT_EQ(parse_error(box + "materials:\n  - {name: a, isotropic: {E: 1e9, nu: 0.3}, rho: 1, region: {z: [1, 0]}}\n"),
            "part.yaml:4: materials[0].region.z: expected [low, high] with low < high, got [1, 0]");
}

}  // namespace
}  // namespace crackle
