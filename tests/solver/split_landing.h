// The Luxo jump with its landing written as one contact term per point (heel and toe) that
// touch down together: two simultaneous impacts that must share one velocity jump.
#pragma once

#include <string>
#include <vector>

#include "core/scene.h"

namespace spacetime::testing {

inline Scene withSplitLanding(Scene scene) {
  std::vector<TermSpec> terms;
  for (const TermSpec& t : scene.terms) {
    if (t.id != "landing") {
      terms.push_back(t);
      continue;
    }
    for (size_t p = 0; p < t.points.size(); ++p) {
      TermSpec part = t;
      part.id = t.id + "_" + std::to_string(p);
      part.points = {t.points[p]};
      terms.push_back(part);
    }
  }
  scene.terms = terms;
  return scene;
}

}  // namespace spacetime::testing
