// The project's own profile templates, authored in code with TemplateBuilder
// on any reference body that has the usual feature curves (the procedural
// mannequin or a MakeHuman body): the design is body-relative (rings of
// nodes at given heights and angles around the torso and legs, at a given
// ease off the skin), so the same function encodes the same garment on
// either kind of reference body.
//
//  - "top": a fitted sleeveless top (hip to neckline, two armholes, 36 quads)
//    with a stand-up collar joined along the yoke line, an inner edge loop of
//    the top (a non-manifold inner-edge joint, seed 000 Fig. 17 II), and a
//    scoop neckline drawn as two 2D strokes in a front view (attached point
//    lists, seed 000 section 4.1.4); its seams are marked on its edges
//    (TemplateBuilder::seam): side and shoulder seams and the yoke line at
//    the front and back, so its pattern is a front and a back body and a
//    front and a back yoke with the collar sewn onto their boundaries;
//  - "skirt": waist to below the knee, flared, with a scalloped hem of
//    cubic Bezier profiles (seed 001 eqs. (6)-(7));
//  - "trousers": a waistband and two legs, three surfaces joined by three
//    joints (waistband-left leg, waistband-right leg, and the crotch seam
//    between the legs; three surfaces meet at the centre front and back).
// Nodes use every encoding mode: feature points (eq. (1)), vertices, edges,
// faces, one-to-one and n-to-one.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <atelier/engine/status.h>
#include <atelier/systems/profile/profile_template.h>
#include <atelier/systems/body/reference_body.h>

namespace atelier {

[[nodiscard]] Expected<ProfileTemplate> make_top_template(const ReferenceBody& body);
[[nodiscard]] Expected<ProfileTemplate> make_skirt_template(const ReferenceBody& body);
[[nodiscard]] Expected<ProfileTemplate> make_trousers_template(const ReferenceBody& body);

/// The three, in that order.
[[nodiscard]] Expected<std::vector<ProfileTemplate>> make_project_templates(const ReferenceBody& body);

}  // namespace atelier
