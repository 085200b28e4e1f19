// Two Luxo lamps in one scene whose contacts do not line up: luxo_jump's lamp, and a copy
// ("luxo2") that lifts off 0.1 s later and lands 0.1 s later. Each lamp alone is a one-character
// scene; together they must solve as they do alone.
#pragma once

#include <tuple>
#include <utility>

#include "core/scene.h"

namespace spacetime::testing {

// luxo_jump's scene (`first`) with its lamp renamed luxo2 and its contacts and clearances moved
// later: by default 0.1 s, so that it takes off at 0.5 s and lands at 0.9 s.
inline Scene laterLamp(const Scene& first, double takeOff = 0.5, double landing = 0.9) {
  Scene second = first;
  second.characters[0].id = "luxo2";
  for (TermSpec& t : second.terms) {
    t.id += "_2";
    t.character = "luxo2";
    if (t.kind == TermKind::Contact && t.start < 0.1) t.end = takeOff;
    else if (t.kind == TermKind::Contact) t.start = landing;
    else if (t.kind == TermKind::Clearance) std::tie(t.start, t.end) = std::pair(takeOff, landing);
  }
  return second;
}

// The characters and terms of both scenes in one (the first one's settings).
inline Scene together(const Scene& a, const Scene& b) {
  Scene both = a;
  both.characters.insert(both.characters.end(), b.characters.begin(), b.characters.end());
  both.terms.insert(both.terms.end(), b.terms.begin(), b.terms.end());
  return both;
}

}  // namespace spacetime::testing
