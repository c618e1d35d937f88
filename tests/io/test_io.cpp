#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <regex>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "io/csv.hpp"
#include "io/files.hpp"
#include "io/vtu.hpp"
#include "mesh/box.hpp"

using namespace crackle;
namespace fs = std::filesystem;

namespace {
fs::path scratch(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("crackle-test-io-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}
}  // namespace

TEST(Files, AtomicWriteLeavesOnlyTheFinishedFile) {
  const fs::path path = scratch("a.txt");
  io::write_file_atomic(path, "first");
  io::write_file_atomic(path, "second");
  EXPECT_EQ(io::read_file(path), "second");
  for (const auto& entry : fs::directory_iterator(path.parent_path())) {
    EXPECT_EQ(entry.path().string().find(".tmp."), std::string::npos) << entry.path();
  }
}

TEST(Files, UnwritablePathIsAnIoErrorAndWritesNothing) {
  const fs::path path = scratch("no-such-dir") / "x.json";
  EXPECT_THROW(io::write_json(path, nlohmann::json{{"a", 1}}), IoError);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_THROW(io::read_file(scratch("missing.txt")), IoError);
}

TEST(Csv, HeaderWithUnitsAndRoundTripNumbers) {
  io::CsvTable table;
  table.add("time [s]", {0.0, 0.1});
  table.add("displacement [m]", {1.0 / 3.0, -2.5e-9});
  const std::string text = io::to_csv(table);
  EXPECT_EQ(text.substr(0, text.find('\n')), "time [s],displacement [m]");
  const std::string second = text.substr(text.rfind('\n', text.size() - 2) + 1);
  EXPECT_EQ(std::stod(second.substr(second.find(',') + 1)), -2.5e-9);
  EXPECT_NE(text.find("0.3333333333333333"), std::string::npos);
  table.columns[1].pop_back();
  EXPECT_THROW(io::write_csv(scratch("bad.csv"), table), IoError);
}

TEST(Vtu, AppendedBlocksMatchTheDeclaredOffsets) {
  mesh::BoxSpec box;
  box.cells = {2, 1, 1};
  box.order = 2;
  mesh::Mesh mesh = mesh::build_box_mesh(box);
  io::PointField displacement{"displacement", 3, std::vector<double>(3 * mesh.n_nodes(), 1.5)};
  const fs::path path = scratch("box.vtu");
  io::write_vtu(path, mesh, {displacement});
  const std::string text = io::read_file(path);
  EXPECT_NE(text.find("NumberOfPoints=\"" + std::to_string(mesh.n_nodes()) + "\""), std::string::npos);
  EXPECT_NE(text.find("NumberOfCells=\"16\""), std::string::npos);  // 2 elements x 2^3 sub-cells
  // Walk the appended data: each declared offset must land on a size header that fits.
  const std::size_t start = text.find("encoding=\"raw\">") ;
  const std::size_t base = text.find('_', start) + 1;
  std::regex offset_pattern("offset=\"([0-9]+)\"");
  std::vector<std::size_t> offsets;
  for (auto it = std::sregex_iterator(text.begin(), text.begin() + start, offset_pattern); it != std::sregex_iterator(); ++it) {
    offsets.push_back(std::stoull((*it)[1]));
  }
  ASSERT_EQ(offsets.size(), 7u);  // displacement, element, region, Points, connectivity, offsets, types
  std::size_t expected = 0;
  for (std::size_t offset : offsets) {
    EXPECT_EQ(offset, expected);
    std::uint64_t bytes;
    std::memcpy(&bytes, text.data() + base + offset, sizeof bytes);
    expected = offset + sizeof bytes + bytes;
  }
  EXPECT_EQ(text.substr(base + expected, 2), "\n ");
  // The first point value of the displacement block is 1.5.
  double first;
  std::memcpy(&first, text.data() + base + 8, sizeof first);
  EXPECT_EQ(first, 1.5);
  EXPECT_THROW(io::write_vtu(scratch("bad.vtu"), mesh, {{"short", 3, {1.0}}}), IoError);
}
