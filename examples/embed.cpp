// Embedding Atelier: regenerate a garment (a detail template, seed 001
// section 6) on bodies held in memory arrays. No file is read or written and
// no global state is used: everything lives in this function's objects, and
// every system gets an explicit ExecContext with a progress callback and a
// cancellation token.
//
// Build against an installed Atelier (see docs/embedding.md):
//   cmake -S examples -B build-example -DCMAKE_PREFIX_PATH=/opt/atelier
//   cmake --build build-example && ./build-example/embed
#include <algorithm>
#include <cstdio>
#include <string_view>
#include <vector>

#include <atelier/engine/exec_context.h>
#include <atelier/storage/builder.h>
#include <atelier/systems/body/body_set.h>
#include <atelier/systems/body/mannequin.h>
#include <atelier/systems/body/mannequin_source.h>
#include <atelier/systems/body/reference_body.h>
#include <atelier/systems/garment/regenerate_garment.h>
#include <atelier/systems/spatial/body_bvh.h>
#include <atelier/systems/view/render.h>
#include <atelier/systems/mesh/fan_triangulation.h>

using namespace atelier;

namespace {

int fail(const char* what, const Status& s) {
  std::fprintf(stderr, "embed: %s: %s\n", what, s.to_string().c_str());
  return 1;
}

// Mean height of a feature curve (where to cut the garment band).
double curve_height(const ReferenceBody& body, std::int32_t id) {
  auto pl = feature_curve_polyline(body, id);
  double y = 0.0;
  if (!pl || pl->empty()) return y;
  for (const Vec3d& p : *pl) y += p.y();
  return y / static_cast<double>(pl->size());
}

}  // namespace

int main() {
  // 1. Bodies in memory: one topology, positions per parameter set. A caller
  //    with its own scans would fill std::vector<Vec3d> the same way (same
  //    node count and face arrays as the reference body).
  auto topology = make_mannequin_topology(MannequinResolution::from_level(3));
  if (!topology) return fail("topology", topology.status());
  auto reference = make_mannequin(MannequinParams{}, *topology);
  if (!reference) return fail("reference body", reference.status());
  std::vector<MannequinParams> params = sample_mannequins(6, /*seed=*/7);
  std::vector<std::vector<Vec3d>> bodies;
  for (const MannequinParams& p : params) {
    auto pos = mannequin_positions(p, *topology);
    if (!pos) return fail("body", pos.status());
    bodies.push_back(std::move(*pos));
  }

  // 2. The garment: a band of skin from mid-thigh to the waist, 8 mm out.
  const double y_waist = curve_height(*reference, kWaist), y_knee = curve_height(*reference, kKneeLeft);
  const double y_thigh = curve_height(*reference, kThighLeft);
  auto garment = skin_band_garment(*reference, 0.5 * (y_thigh + y_knee), y_waist + 0.02, 0.008, 0.40, "shorts");
  if (!garment) return fail("garment", garment.status());
  std::vector<Vec3d> garment_vertices(garment->nodes.position.begin(), garment->nodes.position.end());

  // 3. Progress and cancellation: a callback (called from one thread at a
  //    time) and a shared token any thread may set.
  ExecContext ctx;
  ctx.threads = 0;  // all cores; results do not depend on it
  ctx.progress = [](std::string_view stage, std::size_t done, std::size_t total) {
    std::printf("  %.*s %zu/%zu\n", static_cast<int>(stage.size()), stage.data(), done, total);
  };

  // 4. Encode on the reference body (detail template, clearance, edge
  //    transfer), then the garment pipeline on every body in memory:
  //    batched decoding, the skin's local stretch, the collision pass and
  //    the fit figures (systems/garment/regenerate_garment.h).
  auto family = GarmentFamily::of(*reference);
  if (!family) return fail("family", family.status());
  PolygonSoup soup = polygon_soup(*garment);
  auto shorts = encode_garment(*family, "shorts", soup, {}, ctx);
  if (!shorts) return fail("encode", shorts.status());
  const auto shared_family = std::make_shared<const GarmentFamily>(std::move(*family));
  const auto shared_shorts = std::make_shared<const GarmentTemplate>(std::move(*shorts));
  auto regenerator = GarmentRegenerator::create(shared_family, {shared_shorts}, {}, ctx);
  if (!regenerator) return fail("pipeline", regenerator.status());
  BodySet set(std::make_shared<const ReferenceBody>(*reference));
  for (std::size_t b = 0; b < bodies.size(); ++b)
    if (Status s = set.add("body-" + std::to_string(b), bodies[b]); !s) return fail("body", s);

  std::vector<BodyGarments> fitted;
  double worst_clearance = 1e300;
  std::size_t inside = 0;
  for (std::size_t b = 0; b < set.size(); ++b) {  // one body per call, to report progress per body
    if (ctx.cancelled()) break;
    if (Status s = regenerator->run(set, b, 1, fitted, ctx); !s) return fail("regenerate", s);
    if (!fitted[0].status) return fail("regenerate", fitted[0].status);
    const GarmentQuality& q = fitted[0].garments[0].quality;
    worst_clearance = std::min(worst_clearance, q.min_clearance);
    inside += q.inside;
    ctx.report("bodies", b + 1, bodies.size());
  }
  const std::vector<Vec3d> decoded = fitted[0].garments[0].positions;  // the last body's garment
  auto tris = fan_triangulate(reference->model);
  if (!tris) return fail("triangulate", tris.status());

  // 5. A picture in memory (ray cast, no GPU): the last body and garment.
  BodyBvh body_bvh, garment_bvh;
  auto garment_tris = fan_triangulate(*garment);
  if (!garment_tris) return fail("triangulate garment", garment_tris.status());
  if (Status s = body_bvh.build(bodies.back(), tris->triangles); !s) return fail("bvh", s);
  if (Status s = garment_bvh.build(decoded, garment_tris->triangles); !s) return fail("bvh", s);
  const RenderMesh scene[] = {{&body_bvh, body_colour()}, {&garment_bvh, garment_colour(0)}};
  RenderParams view;
  view.width = 120;
  view.height = 160;
  ExecContext quiet = ctx;
  quiet.progress = nullptr;
  auto picture = render_scene(scene, view, quiet);
  if (!picture) return fail("render", picture.status());
  std::size_t garment_pixels = static_cast<std::size_t>(std::count(picture->mesh.begin(), picture->mesh.end(), 1));

  // 6. Cancellation: a token set from the progress callback stops the work.
  ExecContext cancelling = ctx;
  cancelling.progress = [&](std::string_view, std::size_t done, std::size_t) {
    if (done >= 2) cancelling.cancel.cancel();
  };
  std::size_t decoded_before_cancel = 0;
  for (std::size_t b = 0; b < set.size() && !cancelling.cancelled(); ++b) {
    if (Status s = regenerator->run(set, b, 1, fitted, cancelling); !s) break;
    cancelling.report("bodies", ++decoded_before_cancel, bodies.size());
  }
  auto again = encode_garment(*shared_family, "again", soup, {}, cancelling);
  const bool encode_cancelled = !again && again.status().code() == ErrorCode::kCancelled;

  std::printf("atelier embed: %zu bodies, garment %zu vertices, %zu p-polygon entries\n", bodies.size(),
              garment_vertices.size(), shared_shorts->encoding.entries());
  std::printf("worst clearance %.2f mm, %zu vertices inside a body\n", 1000.0 * worst_clearance, inside);
  std::printf("picture %ux%u: %zu body+garment pixels, %zu garment pixels\n", picture->image.width,
              picture->image.height, picture->covered_pixels, garment_pixels);
  std::printf("cancelled after %zu of %zu bodies; encode %s\n", decoded_before_cancel, bodies.size(),
              encode_cancelled ? "cancelled" : "NOT cancelled");
  return encode_cancelled && decoded_before_cancel == 2 && garment_pixels > 0 ? 0 : 1;
}
