// Collocation grid and quadrature (see transcription.h).
#include "solver/transcription.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace spacetime {

int segmentsFor(double t0, double t1, double rate) {
  // Clamped before rounding: lround of 1e300 overflowed to a single segment. The loader bounds
  // the count far below this (SceneLimits::kMaxSegments).
  return std::max(1, static_cast<int>(std::lround(std::clamp((t1 - t0) * rate, 0.0, 1e8))));
}

namespace {

// Golub-Welsch: the nodes are the eigenvalues of a Jacobi matrix, the weights 2 v0^2 from the
// first components of its eigenvectors.
void golubWelsch(const Eigen::MatrixXd& J, std::vector<double>* nodes, std::vector<double>* weights) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(J);
  const int n = static_cast<int>(J.rows());
  nodes->resize(n);
  weights->resize(n);
  for (int i = 0; i < n; ++i) {
    (*nodes)[i] = es.eigenvalues()[i];
    (*weights)[i] = 2 * es.eigenvectors()(0, i) * es.eigenvectors()(0, i);
  }
}

}  // namespace

void gaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  // The Jacobi matrix of the Legendre recurrence: zero diagonal, k / sqrt(4k^2 - 1) beside it.
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) J(k, k - 1) = J(k - 1, k) = k / std::sqrt(4.0 * k * k - 1);
  golubWelsch(J, nodes, weights);
}

void gaussRadau(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  // Golub-Welsch on the Legendre Jacobi matrix with its last diagonal entry modified so that -1
  // is an eigenvalue (Golub 1973, "Some modified matrix eigenvalue problems"): with the
  // monic recurrence p_{k+1} = x p_k - b_k p_{k-1}, b_k = k^2 / (4k^2 - 1), the entry is
  // a = -1 - b_{n-1} p_{n-2}(-1) / p_{n-1}(-1).
  nodes->assign(n, -1.0);
  weights->assign(n, 2.0);
  if (n == 1) return;
  auto b = [](int k) { return k * k / (4.0 * k * k - 1); };
  std::vector<double> p(n);  // monic Legendre p_k(-1)
  p[0] = 1;
  p[1] = -1;
  for (int k = 1; k + 1 < n; ++k) p[k + 1] = -p[k] - b(k) * p[k - 1];
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) J(k, k - 1) = J(k - 1, k) = std::sqrt(b(k));
  J(n - 1, n - 1) = -1 - b(n - 1) * p[n - 2] / p[n - 1];
  golubWelsch(J, nodes, weights);
  (*nodes)[0] = -1;  // exactly
}

Transcription Transcription::fromScene(const Scene& scene) {
  Transcription tr;
  const double t0 = scene.startTime, t1 = scene.endTime;
  // The refinement's knots where it split segments (those still inside the clip, should the clip
  // have changed since), the scene's rate otherwise.
  std::vector<double> knots = {t0};
  for (double k : scene.transcription.knots)
    if (TranscriptionSpec::knotFollows(knots.back(), k, t1)) knots.push_back(k);
  knots.push_back(t1);
  tr.motion = scene.transcription.knots.empty()
                  ? CubicBSpline(t0, t1, segmentsFor(t0, t1, scene.transcription.controlPointsPerSecond))
                  : CubicBSpline(knots);
  // Breakpoints: the spline's knots and every contact edge inside the clip.
  for (int k = 0; k <= tr.motion.segmentCount(); ++k)
    tr.breakpoints.push_back(tr.motion.knot(k));
  for (const TermSpec& t : scene.terms)
    if (t.enabled && t.kind == TermKind::Contact)
      for (double e : {t.start, t.end})
        if (e > t0 && e < t1) tr.breakpoints.push_back(e);
  std::sort(tr.breakpoints.begin(), tr.breakpoints.end());
  tr.breakpoints.erase(std::unique(tr.breakpoints.begin(), tr.breakpoints.end(),
                                   [](double a, double b) { return std::abs(a - b) < kTimeTolerance; }),
                       tr.breakpoints.end());
  tr.breakpoints.back() = t1;
  std::vector<double> x, w, xr, wr;
  gaussLegendre(scene.transcription.samplesPerSegment, &x, &w);
  gaussRadau(scene.transcription.samplesPerSegment + 1, &xr, &wr);
  // A character's flight starts at breakpoint a when one of its contacts ends there with a fixed
  // end and none of its contacts covers [a, b] or begins at a (see Sample::after). Free contact
  // ends move their breakpoint: they keep Gauss nodes.
  auto liftingOff = [&](double a, double b) {
    std::vector<std::string> ids;
    for (const CharacterSpec& c : scene.characters) {
      bool ends = false, stays = false;
      for (const TermSpec& t : scene.terms) {
        if (!t.enabled || t.kind != TermKind::Contact || t.character != c.id) continue;
        if (std::abs(t.end - a) < kTimeTolerance) (t.freeEnd ? stays : ends) = true;
        if (std::abs(t.start - a) < kTimeTolerance || (t.start < b - kTimeTolerance && t.end > a + kTimeTolerance)) stays = true;
      }
      if (ends && !stays) ids.push_back(c.id);
    }
    return ids;
  };
  auto addNodes = [&](double a, double h, const std::vector<double>& nodes, const std::vector<double>& weights,
                      bool radau, const std::vector<std::string>& only, const std::vector<std::string>& except) {
    for (size_t i = 0; i < nodes.size(); ++i) {
      Sample s;
      s.time = a + h * 0.5 * (nodes[i] + 1);
      s.weight = 0.5 * h * weights[i];
      s.after = radau && i == 0;
      if (s.after) s.time = a;
      s.only = only;
      s.except = except;
      tr.samples.push_back(s);
    }
  };
  for (size_t k = 0; k + 1 < tr.breakpoints.size(); ++k) {
    const double a = tr.breakpoints[k], h = tr.breakpoints[k + 1] - a;
    const std::vector<std::string> lifting = liftingOff(a, a + h);
    if (lifting.empty()) {
      addNodes(a, h, x, w, false, {}, {});
      continue;
    }
    tr.flightStarts.push_back({a, lifting});
    addNodes(a, h, xr, wr, true, lifting, {});
    if (lifting.size() < scene.characters.size()) addNodes(a, h, x, w, false, {}, lifting);
  }
  std::vector<double> extra = {t0, t1};
  for (const TermSpec& t : scene.terms)
    if (t.enabled && t.kind == TermKind::Contact) {
      extra.push_back(t.start);
      extra.push_back(t.end);
    }
  auto zeroWeight = [](double t, bool stance) {
    Sample s;
    s.time = t;
    s.stance = stance;
    return s;
  };
  auto present = [&](double t) {  // a sample read at t on its own contacts' side
    return std::any_of(tr.samples.begin(), tr.samples.end(),
                       [&](const Sample& s) { return !s.after && std::abs(s.time - t) < kTimeTolerance; });
  };
  for (double e : extra)
    if (!present(e)) tr.samples.push_back(zeroWeight(e, false));
  for (const TermSpec& t : scene.terms)
    if (t.enabled && t.kind == TermKind::Contact)
      for (int k = 1; k < tr.motion.segmentCount(); ++k) {
        const double knot = tr.motion.knot(k);
        if (knot > t.start + kTimeTolerance && knot < t.end - kTimeTolerance && !present(knot)) tr.samples.push_back(zeroWeight(knot, true));
      }
  std::sort(tr.samples.begin(), tr.samples.end(),
            [](const Sample& a, const Sample& b) { return a.time < b.time; });
  return tr;
}

bool Sample::appliesTo(const std::string& character) const {
  if (!only.empty()) return std::find(only.begin(), only.end(), character) != only.end();
  return std::find(except.begin(), except.end(), character) == except.end();
}

bool Transcription::flightStartsAt(const std::string& id, double t) const {
  return std::any_of(flightStarts.begin(), flightStarts.end(), [&](const FlightStart& f) {
    return std::abs(f.time - t) < kTimeTolerance && std::find(f.characters.begin(), f.characters.end(), id) != f.characters.end();
  });
}

std::vector<Sample> Transcription::samplesIn(double t0, double t1, const std::string* character) const {
  std::vector<Sample> out;
  for (const Sample& s : samples)
    if (s.time >= t0 - kTimeTolerance && s.time <= t1 + kTimeTolerance && (!character || s.appliesTo(*character))) out.push_back(s);
  return out;
}

std::vector<double> Transcription::denseGrid(int factor) const {
  auto counted = [](const Sample& s) { return !s.stance && s.except.empty(); };
  if (motion.uniform()) {
    const int n = static_cast<int>(std::count_if(samples.begin(), samples.end(), counted)) * factor;
    std::vector<double> grid(n + 1);
    for (int i = 0; i <= n; ++i)
      grid[i] = motion.start() + (motion.end() - motion.start()) * i / n;
    return grid;
  }
  // Non-uniform knots: each segment as finely as its own samples, so that a segment the
  // refinement split is checked as densely as the uniform grid checks its finest rate.
  std::vector<double> grid;
  for (int k = 0; k < motion.segmentCount(); ++k) {
    const double a = motion.knot(k), b = motion.knot(k + 1);
    const int inside = static_cast<int>(std::count_if(samples.begin(), samples.end(), [&](const Sample& s) {
      return counted(s) && s.time >= a - kTimeTolerance && s.time < b - kTimeTolerance;
    }));
    const int n = std::max(1, inside) * factor;
    for (int i = 0; i < n; ++i) grid.push_back(a + (b - a) * i / n);
  }
  grid.push_back(motion.end());
  return grid;
}

}  // namespace spacetime
