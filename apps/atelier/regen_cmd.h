// `atelier encode` and `atelier regen`: the batch job on files.
//
//   atelier encode --template all --reference mannequin --out templates/
//       encodes the project's profile templates on a reference body and
//       writes <name>.template.json (systems/template_json.h) and <name>.obj;
//   atelier encode --garment shorts.obj --reference mannequin --out templates/
//       encodes a garment mesh (OBJ, or a MakeHuman .mhclo binding with
//       --reference makehuman) as a detail template (seed 001 section 6,
//       systems/detail_template.h): templates/shorts.atd and, beside it,
//       templates/shorts.obj, the garment on the reference body (its faces,
//       and the clearance the collision pass restores, systems/collision_pass.h);
//   atelier encode --garment coat.obj --reference my_body.obj --scale 0.01 --up z
//       the same on a user's own reference body (any closed, consistently
//       oriented OBJ; systems/body/body_file.h): the body and the garment
//       are in the file's units and axes, mapped to metres and Y up at the
//       door; the template pair written is in metres and Y up. Profile
//       templates need the body's feature curves: only garments encode on
//       a body without them (docs/body-files.md);
//   atelier encode --template skirt --reference my_body.obj --features curves.json
//       a profile template on a user's body: the named polylines of the
//       JSON file (io/feature_curves.h) are snapped onto the body; `regen
//       --source DIR --reference my_body.obj --features curves.json` snaps
//       them once on the reference, and every body of DIR (same topology)
//       carries them by their locations on its faces;
//   atelier regen --template templates/top.template.json --source mannequin
//       --count 1000 --out run/
//       regenerates every template on every body of a body set, streamed in
//       chunks (a .atd template is decoded, then put through the collision
//       pass; its record has inside nodes, clearance error and strain). Per
//       body, run/bodies/<body>/<template>.obj (first --meshes bodies) and
//       run/bodies/<body>.json, the body's quality record,
//       written last and atomically: an "ok" record marks the body complete,
//       so a rerun of the same job skips it (resume after a kill) and retries
//       failed ones; run/job.json says what the job is, and a rerun of
//       another job into run/ is refused (apps/atelier/regen_job.h). A failing body is recorded with its
//       reason and the others go on (exit code 1). run/report.json merges
//       the records in body order; it holds no timings, so the same inputs
//       and seed give byte-identical outputs for any --threads (timings go to
//       run/timing.json).
//   atelier regen ... --patterns
//       also flattens each regenerated profile template into a made-to-measure
//       pattern set (systems/pattern/made_to_measure.h): per body and
//       template, run/bodies/<body>/patterns/<template>/ holds one SVG per
//       piece, pattern.dxf and measurements.csv, all written before the
//       body's record (which then lists each set's figures under
//       "patterns"); a rerun with --patterns redoes bodies whose record has
//       no "patterns" (complete from a run without them). Pieces are cut
//       along the seams the templates mark (the top: front and back body
//       and yoke); --no-marked-seams ignores the marks.
//   mpirun -np K atelier regen ... (a build with MPI, apps/atelier/mpi_split.h)
//       splits the body set across K ranks, chunk c to rank c mod K; each
//       rank writes its bodies' records into the shared output folder, and
//       after all ranks are done rank 0 alone merges report.json (the same
//       bytes as a one-process run) and timing.json (with each rank's
//       work). The exit code is the worst over the ranks. docs/cluster.md.
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"

namespace atelier::cli {

struct EncodeOptions {
  std::string name;                         // top | skirt | trousers | all ("" = all, or none with --garment)
  std::string reference = "mannequin";      // mannequin | makehuman | a body OBJ file
  std::filesystem::path data = "../shared/data";
  std::filesystem::path out = "templates";
  std::filesystem::path garment;            // .obj or .mhclo: encode as a detail template
  double scale = 1.0;                       // garment (and body file) units to metres
  std::string up = "y";                     // garment (and body file) up axis: y | z
  std::filesystem::path features;           // feature-curve JSON for a body OBJ (profile templates)
  std::optional<int> z_depth;               // the garment's layer order (a .mhclo's own by default)
  bool scaled_frames = false;               // detail template frames that scale with the skin (issue 26)
};
CLI::App* add_encode_subcommand(CLI::App& app, EncodeOptions& opt);
int run_encode(const Common& common, const EncodeOptions& opt, Log& log);

struct RegenOptions {
  std::vector<std::filesystem::path> templates;
  BodiesOptions bodies;  // source, count, data, reference, scale; out is unused
  std::filesystem::path out = "out/regen";
  std::size_t meshes = 0;
  std::size_t chunk = 32;
  int levels = -1;
  double clearance = -1;
  bool no_resume = false;
  bool report = false;    // report.html with pictures (regen_report.h)
  bool patterns = false;  // made-to-measure pattern sets per body (systems/pattern/made_to_measure.h)
  bool no_marked_seams = false;  // --patterns without cutting along the templates' seam marks
};
CLI::App* add_regen_subcommand(CLI::App& app, RegenOptions& opt);
int run_regen(const Common& common, const RegenOptions& opt, Log& log);

}  // namespace atelier::cli
