// The sketch tests' runs over sampled mannequins (the garment, recipe and
// mirror extrusions on 2 or 100 bodies): one loop, in parallel, one body
// per task, so results do not depend on the scheduling.
#pragma once

#include <atelier/engine/exec_context.h>
#include <atelier/engine/parallel.h>
#include <atelier/systems/body/mannequin.h>

#include <cstddef>
#include <vector>

namespace atelier::sketch_test {

/// `f(body)` on the first n mannequins sampled with seed 42. A body that
/// cannot be made gives a default Result whose `error` says why.
template <class Result, class F>
std::vector<Result> on_sampled_mannequins(std::size_t n, F&& f) {
  const auto topo = make_mannequin_topology().value();
  std::vector<Result> got(n);
  ExecContext ctx;
  ctx.sequential_threshold = 2;
  ctx.grain = 1;
  par::for_each_n(ctx, n, [&](std::size_t i) {
    auto body = make_mannequin(sample_mannequin(42, i), topo);
    if (!body) {
      got[i].error = body.status().to_string();
      return;
    }
    got[i] = f(*body);
  });
  return got;
}

}  // namespace atelier::sketch_test
