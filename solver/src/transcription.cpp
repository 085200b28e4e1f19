// Collocation grid and quadrature (see transcription.h).
#include "solver/transcription.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace spacetime {

int segmentsFor(double t0, double t1, double rate) {
  return std::max(1, static_cast<int>(std::lround((t1 - t0) * rate)));
}

void gaussLegendre(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  // Golub-Welsch: the nodes are the eigenvalues of the Jacobi matrix of the Legendre
  // recurrence, the weights 2 v0^2 from the first components of its eigenvectors.
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) J(k, k - 1) = J(k - 1, k) = k / std::sqrt(4.0 * k * k - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(J);
  nodes->resize(n);
  weights->resize(n);
  for (int i = 0; i < n; ++i) {
    (*nodes)[i] = es.eigenvalues()[i];
    (*weights)[i] = 2 * es.eigenvectors()(0, i) * es.eigenvectors()(0, i);
  }
}

Transcription Transcription::fromScene(const Scene& scene) {
  Transcription tr;
  const double t0 = scene.startTime, t1 = scene.endTime;
  tr.motion = UniformBSpline(t0, t1, segmentsFor(t0, t1, scene.transcription.controlPointsPerSecond));
  // Breakpoints: the spline's knots and every contact edge inside the clip.
  for (int k = 0; k <= tr.motion.segmentCount(); ++k)
    tr.breakpoints.push_back(t0 + k * tr.motion.knotSpacing());
  for (const TermSpec& t : scene.terms)
    if (t.enabled && t.kind == TermKind::Contact)
      for (double e : {t.start, t.end})
        if (e > t0 && e < t1) tr.breakpoints.push_back(e);
  std::sort(tr.breakpoints.begin(), tr.breakpoints.end());
  tr.breakpoints.erase(std::unique(tr.breakpoints.begin(), tr.breakpoints.end(),
                                   [](double a, double b) { return std::abs(a - b) < 1e-9; }),
                       tr.breakpoints.end());
  tr.breakpoints.back() = t1;
  std::vector<double> x, w;
  gaussLegendre(scene.transcription.samplesPerSegment, &x, &w);
  for (size_t k = 0; k + 1 < tr.breakpoints.size(); ++k) {
    const double a = tr.breakpoints[k], h = tr.breakpoints[k + 1] - a;
    for (size_t i = 0; i < x.size(); ++i) tr.samples.push_back({a + h * 0.5 * (x[i] + 1), 0.5 * h * w[i]});
  }
  std::vector<double> extra = {t0, t1};
  for (const TermSpec& t : scene.terms)
    if (t.enabled && t.kind == TermKind::Contact) {
      extra.push_back(t.start);
      extra.push_back(t.end);
    }
  auto present = [&](double t) {
    return std::any_of(tr.samples.begin(), tr.samples.end(),
                       [&](const Sample& s) { return std::abs(s.time - t) < 1e-9; });
  };
  for (double e : extra)
    if (!present(e)) tr.samples.push_back({e, 0.0});
  for (const TermSpec& t : scene.terms)
    if (t.enabled && t.kind == TermKind::Contact)
      for (int k = 1; k < tr.motion.segmentCount(); ++k) {
        const double knot = t0 + k * tr.motion.knotSpacing();
        if (knot > t.start + 1e-9 && knot < t.end - 1e-9 && !present(knot)) tr.samples.push_back({knot, 0.0, true});
      }
  std::sort(tr.samples.begin(), tr.samples.end(),
            [](const Sample& a, const Sample& b) { return a.time < b.time; });
  return tr;
}

std::vector<Sample> Transcription::samplesIn(double t0, double t1) const {
  std::vector<Sample> out;
  for (const Sample& s : samples)
    if (s.time >= t0 - 1e-9 && s.time <= t1 + 1e-9) out.push_back(s);
  return out;
}

std::vector<double> Transcription::denseGrid(int factor) const {
  const int n = static_cast<int>(std::count_if(samples.begin(), samples.end(),
                                               [](const Sample& s) { return !s.stance; })) * factor;
  std::vector<double> grid(n + 1);
  for (int i = 0; i <= n; ++i)
    grid[i] = motion.start() + (motion.end() - motion.start()) * i / n;
  return grid;
}

}  // namespace spacetime
