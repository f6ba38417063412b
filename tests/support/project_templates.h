// The default mannequin with the project's three profile templates encoded
// on it, built once per test binary (shared by the regeneration and the
// template-format tests).
#pragma once

#include <vector>

#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/profile/project_templates.h>

namespace atelier::testing {

struct TemplateFixture {
  MannequinTopology topo;
  ReferenceBody body;
  std::vector<ProfileTemplate> templates;  // top, skirt, trousers
};

inline const TemplateFixture& template_fixture() {
  static const TemplateFixture f = [] {
    TemplateFixture x;
    x.topo = make_mannequin_topology().value();
    x.body = make_mannequin(MannequinParams{}, x.topo).value();
    x.templates = make_project_templates(x.body).value();
    return x;
  }();
  return f;
}

}  // namespace atelier::testing
