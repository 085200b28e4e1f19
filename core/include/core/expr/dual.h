// A forward-mode dual number (value + one directional derivative), enough to run the tape's
// reverse sweep in forward mode: forward-over-reverse gives Hessian-vector products
// (Griewank & Walther, "Evaluating Derivatives", ch. 5).
#pragma once

#include <cmath>

namespace spacetime::expr {

struct Dual {
  double v = 0, d = 0;
  Dual() = default;
  Dual(double value, double derivative = 0) : v(value), d(derivative) {}  // NOLINT
};

inline Dual operator+(Dual a, Dual b) { return {a.v + b.v, a.d + b.d}; }
inline Dual operator-(Dual a, Dual b) { return {a.v - b.v, a.d - b.d}; }
inline Dual operator*(Dual a, Dual b) { return {a.v * b.v, a.d * b.v + a.v * b.d}; }
inline Dual operator/(Dual a, Dual b) { return {a.v / b.v, (a.d * b.v - a.v * b.d) / (b.v * b.v)}; }
inline Dual operator-(Dual a) { return {-a.v, -a.d}; }
inline Dual& operator+=(Dual& a, Dual b) { return a = a + b; }
inline Dual& operator-=(Dual& a, Dual b) { return a = a - b; }
inline bool operator<(Dual a, Dual b) { return a.v < b.v; }
inline bool operator>(Dual a, Dual b) { return a.v > b.v; }
inline bool operator>=(Dual a, Dual b) { return a.v >= b.v; }
inline bool operator==(Dual a, Dual b) { return a.v == b.v; }
inline Dual sin(Dual a) { return {std::sin(a.v), a.d * std::cos(a.v)}; }
inline Dual cos(Dual a) { return {std::cos(a.v), -a.d * std::sin(a.v)}; }
inline Dual tan(Dual a) {
  const double t = std::tan(a.v);
  return {t, a.d * (1 + t * t)};
}
inline Dual exp(Dual a) {
  const double e = std::exp(a.v);
  return {e, a.d * e};
}
inline Dual log(Dual a) { return {std::log(a.v), a.d / a.v}; }
inline Dual sqrt(Dual a) {
  const double s = std::sqrt(a.v);
  return {s, a.d / (2 * s)};
}
inline Dual abs(Dual a) { return a.v >= 0 ? a : -a; }
inline Dual pow(Dual a, Dual b) {
  const double p = std::pow(a.v, b.v);
  const double dlog = a.v > 0 ? b.d * std::log(a.v) : 0.0;
  return {p, p * dlog + b.v * std::pow(a.v, b.v - 1) * a.d};
}

}  // namespace spacetime::expr
