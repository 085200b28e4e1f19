// The time discretisation of a spacetime problem: one uniform cubic B-spline layout shared by
// every degree of freedom of every character, and the collocation samples where physics and the
// objective are evaluated.
//
// Breakpoints are the spline's knots plus every contact edge. Samples are Gauss-Legendre nodes
// inside every interval between breakpoints (two by default: the collocation of de Boor &
// Swartz 1973 for the root's C1 piecewise cubics, and exact quadrature of the particle's
// piecewise-quadratic integrands) - except the interval that starts a flight after a fixed
// lift-off, which gets one more node, left Gauss-Radau, the first at the lift-off itself on the
// flight side (Sample::after), for the characters whose flight starts there (other characters
// keep Gauss nodes on that interval) - plus the clip's ends and every contact edge with zero
// quadrature weight: physics must hold at the instants where contact begins and ends; plus
// "stance" samples at the knots inside each contact (zero weight, see Sample::stance).
#pragma once

#include <string>
#include <vector>

#include "core/bspline.h"
#include "core/scene.h"

namespace spacetime {

// Two instants closer than this are the same (contact edges, samples, breakpoints).
inline constexpr double kTimeTolerance = 1e-9;

// How many times denser than the samples the validity report's grid is (Transcription::denseGrid).
inline constexpr int kDenseGridFactor = 10;

struct Sample {
  double time = 0;
  double weight = 0;  // quadrature weight (0 for the extra boundary samples)
  // A knot inside a contact interval (zero weight): physics and the friction cone are imposed
  // there only for a character whose root that contact holds still (see
  // SpacetimeProblem::physicsAt). The joints' jerk jumps at knots, so the ground force a stance
  // needs has a kink there, which the Gauss points on either side do not see.
  bool stance = false;
  // The first instant of a flight: evaluated on the root interval that starts at `time`, without
  // the contacts ending there. The interval after a lift-off is collocated at left Gauss-Radau
  // nodes, whose first node is this instant: the root's acceleration jumps at the lift-off
  // breakpoint, and Gauss nodes left the flight's first instants free (luxo_jump: 0.0052 x
  // weight unexplained just after lift-off).
  bool after = false;
  // The characters (ids) this sample is for: every one, or only those whose flight starts at the
  // interval's start (its Radau nodes), or all but those (its Gauss nodes). Two lamps lifting off
  // 0.1 s apart: the first lamp's flight is collocated from its first instant while the second,
  // still standing, keeps its own nodes (with Radau nodes for both, the first lamp's dense-grid
  // residual drops 0.0049 -> 0.0017 x weight, but the standing lamp's optimum moves 0.33 %).
  std::vector<std::string> only, except;
  bool appliesTo(const std::string& character) const;
};

// Where some characters' flights start after a fixed lift-off (see Sample::after).
struct FlightStart {
  double time = 0;
  std::vector<std::string> characters;  // whose flight starts here
};

struct Transcription {
  CubicBSpline motion;            // the actuated joints' spline
  std::vector<double> breakpoints;  // knots and contact edges, sorted
  std::vector<Sample> samples;      // sorted by time
  // Breakpoints where a flight starts after a fixed lift-off: for the characters lifting off,
  // the interval from there gets s + 1 left Gauss-Radau nodes (the first read on the flight side,
  // Sample::after) and the root one more bubble there (SpacetimeProblem).
  std::vector<FlightStart> flightStarts;
  // Whether character `id`'s flight starts at breakpoint t.
  bool flightStartsAt(const std::string& id, double t) const;

  static Transcription fromScene(const Scene& scene);
  // Samples whose time lies in [t0, t1] (inclusive, with a small tolerance); with a character
  // id, only those for that character (Sample::appliesTo).
  std::vector<Sample> samplesIn(double t0, double t1, const std::string* character = nullptr) const;
  // A uniform grid with `factor` times as many points as there are samples (stance samples
  // and the Gauss nodes kept for the other characters where some flights start not counted);
  // on non-uniform knots, each knot interval evenly with `factor` times its own samples.
  std::vector<double> denseGrid(int factor) const;
};

// Segments of a spline over [t0, t1] at `rate` control points per second (at least one).
int segmentsFor(double t0, double t1, double rate);

// Gauss-Legendre nodes on [-1, 1] and weights, for 1 <= n <= 16 (Golub-Welsch).
void gaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights);
// Left Gauss-Radau nodes on [-1, 1] (the first is -1) and weights, for 1 <= n <= 16: exact for
// polynomials of degree 2n - 2.
void gaussRadau(int n, std::vector<double>* nodes, std::vector<double>* weights);

}  // namespace spacetime
