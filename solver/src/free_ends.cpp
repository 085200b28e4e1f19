// Free contact ends: the window of a lift-off instant, where its times lie as it moves, the
// checks of what a scene may time inside it, and bringing the problem's times to its solved value
// (see spacetime_problem.h: "Free contact ends").
#include <algorithm>
#include <cmath>
#include <string>

#include "solver/spacetime_problem.h"

namespace spacetime {

double FreeEnd::map(double t0, double from, double to) const {
  if (std::abs(t0 - from) < kTimeTolerance) return to;
  if (t0 <= left || t0 >= right) return t0;
  if (t0 < from) return left + (t0 - left) * (to - left) / (from - left);
  return to + (t0 - from) * (right - to) / (right - from);
}

double FreeEnd::rate(double t0, double from) const {
  if (std::abs(t0 - from) < kTimeTolerance) return 1;
  if (t0 <= left || t0 >= right) return 0;
  return t0 < from ? (t0 - left) / (from - left) : (right - t0) / (right - from);
}

TimeRef SpacetimeProblem::timeRef(int c, double t, Side side) const {
  TimeRef r;
  r.time = t;
  r.rootSide = side;
  const DofGroup* g = rootGroup(c);
  // A flight's first instant at a window's end reads the flight's interval: if that lies outside
  // the window the time is fixed. (Judged on the stance side it moved, and read the stance's
  // interval: a lamp lifting off at another lamp's free-end window's end left its first flight
  // interval one row short - 332 x weight between the samples.)
  const int k = g ? hermiteInterval(c, *g, t, side) : -1;
  for (size_t i = 0; i < freeEnds_.size(); ++i) {
    const FreeEnd& e = freeEnds_[i];
    if (t < e.left - kTimeTolerance || t > e.right + kTimeTolerance) continue;
    TimeRef m = r;
    m.event = static_cast<int>(i);
    m.eventTime = e.current;
    m.rate = e.rate(t, e.current);
    m.side = std::abs(t - e.current) < kTimeTolerance ? 0 : t < e.current ? -1 : 1;
    m.interval = k;
    if (g) {
      m.intervalStart = g->breaks[k];
      m.intervalEnd = g->breaks[k + 1];
    }
    // A time at the window's end moves nothing unless its root interval lies inside the window.
    const bool moves = m.rate > 0 || (g && (e.rate(m.intervalStart, e.current) > 0 ||
                                            e.rate(m.intervalEnd, e.current) > 0));
    if (moves) return m;
  }
  return r;
}

bool SpacetimeProblem::addFreeEnds(std::string* error, int* size) {
  for (size_t j = 0; j < contacts_.size(); ++j) {
    ContactVariables& ct = contacts_[j];
    const TermSpec& spec = scene_.terms[ct.term];
    if (!spec.freeEnd) continue;
    const std::string label = "term '" + spec.id + "': a free end (freeEnd)";
    const DofGroup* g = rootGroup(ct.character);
    if (!g) {
      *error = label + " needs a floating character: lifting off moves its root";
      return false;
    }
    if (ct.end >= scene_.endTime - kTimeTolerance) {
      *error = label + " needs a contact that ends before the clip does";
      return false;
    }
    // The window: the root breakpoints at least freeEndWindow before and after the end - by
    // default the neighbouring ones, so only the lift-off itself moves. Breakpoints inside a
    // wider window move with T, away from the joints' knots where the joints' jerk jumps, and
    // the root then cannot follow that kink (luxo_jump at s = 6: dense-grid residual 0.14 x
    // weight with a 0.1 s window, 0.001 with the default).
    const auto& tb = transcription_.breakpoints;
    const double w = std::max(spec.freeEndWindow, 2 * kTimeTolerance);
    FreeEnd e;
    e.contact = static_cast<int>(j);
    e.character = ct.character;
    e.left = tb.front();
    e.right = tb.back();
    for (double b : tb) {
      if (b <= ct.end - w + kTimeTolerance) e.left = b;
    }
    for (auto b = tb.rbegin(); b != tb.rend(); ++b)
      if (*b >= ct.end + w - kTimeTolerance) e.right = *b;
    e.current = ct.end;
    // Keep each side of the window at least a fifth of its length.
    e.lower = e.left + 0.2 * (ct.end - e.left);
    e.upper = e.right - 0.2 * (e.right - ct.end);
    if (ct.start > e.left + kTimeTolerance) {
      *error = label + " needs the contact to cover the root interval before its end (it starts at " +
               std::to_string(ct.start) + " s, the interval at " + std::to_string(e.left) + " s)";
      return false;
    }
    for (const FreeEnd& other : freeEnds_)
      if (other.left < e.right - kTimeTolerance && e.left < other.right - kTimeTolerance) {
        *error = label + " lies too close to the free end of term '" +
                 scene_.terms[contacts_[other.contact].term].id + "': their windows (" +
                 std::to_string(other.left) + "-" + std::to_string(other.right) + " s and " +
                 std::to_string(e.left) + "-" + std::to_string(e.right) + " s) overlap";
        return false;
      }
    for (const ContactVariables& other : contacts_)
      if (other.impact() && other.start > e.left - kTimeTolerance && other.start < e.right + kTimeTolerance) {
        *error = label + " has a touch-down inside its window (" + std::to_string(e.left) + "-" +
                 std::to_string(e.right) + " s)";
        return false;
      }
    e.offset = (*size)++;
    ct.freeEnd = static_cast<int>(freeEnds_.size());
    freeEnds_.push_back(e);
  }
  return true;
}

bool SpacetimeProblem::checkOutsideWindows(double t, const std::string& label, std::string* error) const {
  for (const FreeEnd& e : freeEnds_)
    if (t > e.left + kTimeTolerance && t < e.right - kTimeTolerance &&
        std::abs(t - e.current) > kTimeTolerance) {
      *error = label + " at t=" + std::to_string(t) + " lies inside the lift-off window (" +
               std::to_string(e.left) + "-" + std::to_string(e.right) + " s) of the free end of term '" +
               scene_.terms[contacts_[e.contact].term].id +
               "': move it out of the window or onto the contact's end";
      return false;
    }
  return true;
}

void SpacetimeProblem::syncFreeEnds() {
  for (FreeEnd& e : freeEnds_) {
    const double T = x_[e.offset], was = e.current;
    if (T == was) continue;
    auto same = [&](double t) { return std::abs(t - was) < kTimeTolerance; };
    auto move = [&](double t) { return e.map(t, was, T); };
    for (CharacterVariables& cv : characters_)
      for (DofGroup& g : cv.groups)
        if (g.hermite)
          for (double& b : g.breaks) b = move(b);
    for (double& b : transcription_.breakpoints) b = move(b);
    for (Sample& smp : transcription_.samples) {
      if (smp.time > e.left && smp.time < was && !same(smp.time)) smp.weight *= (T - e.left) / (was - e.left);
      if (smp.time > was && smp.time < e.right && !same(smp.time)) smp.weight *= (e.right - T) / (e.right - was);
      smp.time = move(smp.time);
    }
    for (ContactVariables& ct : contacts_) {
      ct.start = move(ct.start);
      ct.end = move(ct.end);
      for (double& t : ct.times) t = move(t);
    }
    e.current = T;
  }
}

}  // namespace spacetime
