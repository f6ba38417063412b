// Internals shared by the two sources of the template JSON format
// (systems/profile/template_json.h):
//
//   template_json_write.cpp  to_json and the pretty printer
//   template_json_read.cpp   the reader and from_json
#pragma once

#include <atelier/systems/profile/profile_template.h>

namespace atelier::template_json_detail {

/// The largest `levels` a template file may give: the writer refuses what
/// the reader would.
inline constexpr int kMaxLevels = kMaxTemplateLevels;

}  // namespace atelier::template_json_detail
