// How often a running solve hands a live iterate to the interface. Each one costs the interface
// a redraw of the viewport and a composite of the whole window; where that runs on the CPU (a
// software OpenGL renderer: Xvfb, a virtual machine, a remote desktop) the renderer's threads
// take the cores the solver needs, and the solver runs at idle priority. Measured with
// `spacetime --screenshot` under Xvfb on the shipped jump at s = 3: 26.3 s to solve with an
// iterate every 250 ms, 8.5 s with one a second, 6 s with none.
//
// So the interval adapts to the share of the wall-clock time the solver thread got since the
// last iterate (its CPU time over the wall time): below kStarved the interval doubles, up to
// the longest; above kFed it halves, down to the shortest. With a GPU the share stays near one and
// the view keeps its 4 iterates a second.
#pragma once

#include <algorithm>

namespace spacetime::ui {

class LivePacing {
 public:
  explicit LivePacing(double shortestSeconds, double longestSeconds = 2.0)
      : shortest_(shortestSeconds), longest_(std::max(shortestSeconds, longestSeconds)), interval_(shortestSeconds) {}

  // Starts the clock: wall time and the solver thread's CPU time, in seconds from any origin.
  void start(double wall, double cpu) {
    lastWall_ = wall;
    lastCpu_ = cpu;
  }

  // Whether an iterate is due at wall time `wall` with the solver thread's CPU time `cpu`.
  bool due(double wall, double cpu) {
    const double elapsed = wall - lastWall_;
    if (elapsed < interval_) return false;
    const double share = (cpu - lastCpu_) / elapsed;
    if (share < kStarved) interval_ = std::min(longest_, 2 * interval_);
    else if (share > kFed) interval_ = std::max(shortest_, 0.5 * interval_);
    lastWall_ = wall;
    lastCpu_ = cpu;
    return true;
  }

  double interval() const { return interval_; }

  static constexpr double kStarved = 0.75;  // the interface took more than a quarter of the solver's core
  static constexpr double kFed = 0.9;

 private:
  double shortest_, longest_, interval_;
  double lastWall_ = 0, lastCpu_ = 0;
};

}  // namespace spacetime::ui
