// The malformed corpus: one small file per problem in tests/data/malformed,
// each with the message fragments its error must carry (the file name is
// always required too). Every file in the folder must be listed, so a new
// bad file cannot be added without saying what it should report.
#include <gtest/gtest.h>

#include <set>

#include <atelier/io/native.h>
#include <atelier/io/obj.h>
#include <atelier/io/off.h>
#include <atelier/io/ply.h>
#include "io_test_support.h"

using namespace atelier;
using namespace atelier::test;

namespace {

struct Case {
  const char* file;
  std::vector<std::string> fragments;
};

const std::vector<Case>& corpus() {
  static const std::vector<Case> cases = {
      {"obj_index_zero.obj", {"line 4", "bad index", "index 0"}},
      {"obj_index_out_of_range.obj", {"line 4", "vertex index 7 out of range"}},
      {"obj_relative_before_first.obj", {"line 4", "-5 refers before the first vertex"}},
      {"obj_nan_coordinate.obj", {"line 2", "NaN/inf coordinate 'nan'"}},
      {"obj_inf_coordinate.obj", {"line 3", "NaN/inf coordinate 'inf'"}},
      {"obj_face_too_few.obj", {"line 4", "face has 2 vertices"}},
      {"obj_non_numeric_vertex.obj", {"line 2", "non-numeric token 'abc'"}},
      {"obj_non_numeric_index.obj", {"line 4", "non-numeric token 'x'"}},
      {"obj_vertex_too_few_coords.obj", {"line 2", "vertex has 2 coordinates"}},
      {"obj_texture_out_of_range.obj", {"line 5", "texture index 9 out of range"}},
      {"obj_nonmanifold_edge.obj", {"shared by 3 faces", "line 7", "line 8", "line 9"}},
      {"obj_inconsistent_orientation.obj", {"same direction", "line 5", "line 6"}},
      {"obj_repeated_vertex.obj", {"twice", "line 5"}},
      {"ply_wrong_magic.ply", {"line 1", "wrong header", "does not start with 'ply'"}},
      {"ply_unknown_format.ply", {"line 2", "unknown PLY format 'binary_middle_endian'"}},
      {"ply_no_end_header.ply", {"line 5", "wrong header", "end_header"}},
      {"ply_unknown_type.ply", {"line 4", "unknown property type 'float128'"}},
      {"ply_missing_xyz.ply", {"header", "lacks scalar x, y and z"}},
      {"ply_no_vertex_element.ply", {"header", "no 'vertex' element"}},
      {"ply_face_no_list.ply", {"header", "no 'vertex_indices' list"}},
      {"ply_ascii_truncated.ply", {"line 13", "element 'face' 0", "element count mismatch"}},
      {"ply_ascii_extra_data.ply", {"line 14", "element count mismatch"}},
      {"ply_ascii_bad_index.ply", {"line 13", "element 'face' 0", "vertex index 9 out of range"}},
      {"ply_ascii_nan.ply", {"line 11", "element 'vertex' 1", "NaN/inf coordinate"}},
      {"ply_ascii_non_numeric.ply", {"line 11", "element 'vertex' 1", "non-numeric token 'zero'"}},
      {"ply_ascii_face_too_few.ply", {"line 13", "face has 2 vertices"}},
      {"ply_binary_truncated.ply", {"byte offset 210", "element 'face' 0", "truncated binary file"}},
      {"ply_binary_bad_index.ply", {"byte offset 214", "element 'face' 0", "vertex index 7 out of range"}},
      {"ply_binary_trailing.ply", {"byte offset 218", "element count mismatch", "3 bytes follow"}},
      {"ply_binary_nan.ply", {"byte offset 185", "element 'vertex' 1", "NaN/inf coordinate"}},
      {"off_wrong_header.off", {"line 1", "wrong header", "expected 'OFF'"}},
      {"off_4d.off", {"line 1", "unsupported OFF variant '4OFF'"}},
      {"off_too_few_vertices.off", {"element count mismatch", "ends after 0 of 1 faces"}},
      {"off_extra_data.off", {"line 7", "element count mismatch"}},
      {"off_bad_index.off", {"line 6", "vertex index 3 out of range"}},
      {"off_nan.off", {"line 5", "NaN/inf coordinate '-inf'"}},
      {"off_face_too_few.off", {"line 6", "face 0 has 2 vertices"}},
      {"off_non_numeric.off", {"line 5", "non-numeric token 'O'"}},
      {"off_missing_counts.off", {"line 2", "missing the vertex/face/edge counts"}},
      {"atm_bad_magic.atm", {"byte offset 0", "bad magic"}},
  };
  return cases;
}

Model read_any(const std::filesystem::path& p) {
  const std::string ext = p.extension().string();
  if (ext == ".obj") return read_obj(p);
  if (ext == ".ply") return read_ply(p);
  if (ext == ".off") return read_off(p);
  if (ext == ".atm") return read_model(p);
  throw std::runtime_error("no reader for " + p.string());
}

const std::filesystem::path kDir = std::filesystem::path(ATELIER_TEST_DATA) / "malformed";

}  // namespace

class Malformed : public ::testing::TestWithParam<Case> {};

TEST_P(Malformed, GivesItsSpecificMessage) {
  const Case& c = GetParam();
  const std::filesystem::path p = kDir / c.file;
  ASSERT_TRUE(std::filesystem::exists(p)) << p;
  auto fragments = c.fragments;
  fragments.push_back(c.file);
  expect_error([&] { (void)read_any(p); }, ErrorCode::kParse, fragments);
}

INSTANTIATE_TEST_SUITE_P(Corpus, Malformed, ::testing::ValuesIn(corpus()), [](const auto& info) {
  std::string n = info.param.file;
  for (char& ch : n)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return n;
});

TEST(MalformedCorpus, EveryFileIsListed) {
  std::set<std::string> listed;
  for (const Case& c : corpus()) listed.insert(c.file);
  for (const auto& e : std::filesystem::directory_iterator(kDir))
    EXPECT_TRUE(listed.count(e.path().filename().string())) << e.path() << " has no expected message";
  EXPECT_EQ(listed.size(), corpus().size()) << "a file is listed twice";
}
