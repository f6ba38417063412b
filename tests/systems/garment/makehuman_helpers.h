// MakeHuman's helper geometry (the "helper-tights" and "helper-skirt" groups
// of base.obj, moved by the same targets as the skin): shared by the
// garment tests that regenerate the helpers and compare with MakeHuman.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <atelier/io/makehuman/makehuman.h>

namespace atelier::garment_test {

/// The base-mesh vertices a group's faces use, sorted, each once.
inline std::vector<std::uint32_t> group_vertices(const makehuman::BaseMesh::Group& group) {
  std::vector<std::uint32_t> v(group.face_nodes.begin(), group.face_nodes.end());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

}  // namespace atelier::garment_test
