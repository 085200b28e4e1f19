// Spatial (6D) vector algebra after Featherstone, "Rigid Body Dynamics Algorithms" (RBDA), ch. 2.
//
// Motion and force vectors are stored as an angular and a linear 3-vector in Plücker coordinates,
// transforms as a rotation E and a translation r and applied without forming 6x6 matrices
// (RBDA Table 2.1 / Table 2.2). Everything is templated on the scalar so the same code runs with
// double, ceres::Jet (exact derivatives) and the symbolic scalar. Functions that combine a
// constant (model) quantity with a variable one take two scalar types, so a double inertia can
// multiply a Jet velocity without promoting the constant to a Jet.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace spacetime {

template <class T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3>;
template <class T>
using Vec6 = Eigen::Matrix<T, 6, 1>;
template <class T>
using Mat6 = Eigen::Matrix<T, 6, 6>;
template <class T>
using VecX = Eigen::Matrix<T, Eigen::Dynamic, 1>;
template <class T>
using MatX = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic>;

// The skew-symmetric matrix with skew(a) * b = a x b.
template <class T>
Mat3<T> skew(const Vec3<T>& a) {
  Mat3<T> m;
  m << T(0), -a.z(), a.y(), a.z(), T(0), -a.x(), -a.y(), a.x(), T(0);
  return m;
}

// Cross product of vectors whose scalar types may differ (constant x variable).
template <class T, class A, class B>
Vec3<T> cross3(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  return Vec3<T>(T(a.y() * b.z() - a.z() * b.y()), T(a.z() * b.x() - a.x() * b.z()),
                 T(a.x() * b.y() - a.y() * b.x()));
}

// A spatial motion vector (angular velocity w, linear velocity v of the body-fixed point at the
// frame origin).
template <class T>
struct Motion {
  Vec3<T> ang = Vec3<T>::Zero();
  Vec3<T> lin = Vec3<T>::Zero();
  Motion() = default;
  Motion(const Vec3<T>& a, const Vec3<T>& l) : ang(a), lin(l) {}
  static Motion Zero() { return Motion(); }
  Motion operator+(const Motion& o) const { return {ang + o.ang, lin + o.lin}; }
  Motion operator-(const Motion& o) const { return {ang - o.ang, lin - o.lin}; }
  Motion& operator+=(const Motion& o) {
    ang += o.ang;
    lin += o.lin;
    return *this;
  }
  Motion operator*(const T& s) const { return {ang * s, lin * s}; }
  Vec6<T> vector() const {
    Vec6<T> v;
    v << ang, lin;
    return v;
  }
  template <class U>
  Motion<U> cast() const {
    return {ang.template cast<U>(), lin.template cast<U>()};
  }
};

// A spatial force vector (moment n about the frame origin, force f).
template <class T>
struct Force {
  Vec3<T> ang = Vec3<T>::Zero();
  Vec3<T> lin = Vec3<T>::Zero();
  Force() = default;
  Force(const Vec3<T>& a, const Vec3<T>& l) : ang(a), lin(l) {}
  static Force Zero() { return Force(); }
  Force operator+(const Force& o) const { return {ang + o.ang, lin + o.lin}; }
  Force operator-(const Force& o) const { return {ang - o.ang, lin - o.lin}; }
  Force& operator+=(const Force& o) {
    ang += o.ang;
    lin += o.lin;
    return *this;
  }
  Force& operator-=(const Force& o) {
    ang -= o.ang;
    lin -= o.lin;
    return *this;
  }
  Vec6<T> vector() const {
    Vec6<T> v;
    v << ang, lin;
    return v;
  }
};

// Scalar product m . f (power), RBDA eq. 2.9.
template <class T>
T dot(const Motion<T>& m, const Force<T>& f) {
  return m.ang.dot(f.ang) + m.lin.dot(f.lin);
}

// Spatial cross products, RBDA eqs. 2.31-2.33: v x m and v x* f.
template <class T>
Motion<T> crossMotion(const Motion<T>& v, const Motion<T>& m) {
  return {v.ang.cross(m.ang), v.ang.cross(m.lin) + v.lin.cross(m.ang)};
}
template <class T>
Force<T> crossForce(const Motion<T>& v, const Force<T>& f) {
  return {v.ang.cross(f.ang) + v.lin.cross(f.lin), v.ang.cross(f.lin)};
}

// A Plücker transform B_X_A from frame A coordinates to frame B coordinates: E rotates A
// coordinates into B coordinates and r is the position of B's origin expressed in A.
// RBDA Table 2.2 (X = rot(E) xlt(r)).
template <class T>
struct Transform {
  Mat3<T> E = Mat3<T>::Identity();
  Vec3<T> r = Vec3<T>::Zero();

  static Transform Identity() { return Transform(); }
  Transform() = default;
  Transform(const Mat3<T>& e, const Vec3<T>& rr) : E(e), r(rr) {}

  Motion<T> apply(const Motion<T>& m) const {
    return {E * m.ang, E * (m.lin - r.cross(m.ang))};
  }
  Force<T> apply(const Force<T>& f) const { return {E * (f.ang - r.cross(f.lin)), E * f.lin}; }
  // The inverse transform applied, A_X_B m.
  Motion<T> applyInverse(const Motion<T>& m) const {
    Vec3<T> w = E.transpose() * m.ang;
    return {w, E.transpose() * m.lin + r.cross(w)};
  }
  Force<T> applyInverse(const Force<T>& f) const {
    Vec3<T> fl = E.transpose() * f.lin;
    return {E.transpose() * f.ang + r.cross(fl), fl};
  }
  // (this: C_X_B) * (other: B_X_A) = C_X_A.
  Transform operator*(const Transform& other) const {
    return Transform(E * other.E, other.r + other.E.transpose() * r);
  }
  Transform inverse() const { return Transform(E.transpose(), -(E * r)); }

  // Point p given in A coordinates, expressed in B coordinates (a pose change, not a vector).
  Vec3<T> transformPoint(const Vec3<T>& p) const { return E * (p - r); }
  // Point p given in B coordinates, expressed in A coordinates.
  Vec3<T> inverseTransformPoint(const Vec3<T>& p) const { return E.transpose() * p + r; }

  Mat6<T> matrix() const {
    Mat6<T> X = Mat6<T>::Zero();
    X.template topLeftCorner<3, 3>() = E;
    X.template bottomRightCorner<3, 3>() = E;
    X.template bottomLeftCorner<3, 3>() = -E * skew(r);
    return X;
  }
  template <class U>
  Transform<U> cast() const {
    return Transform<U>(E.template cast<U>(), r.template cast<U>());
  }
};

// Compose a variable transform with a constant one: (joint: C_X_B, variable) * (tree: B_X_A,
// constant) without promoting the constant part.
template <class T, class S>
Transform<T> compose(const Transform<T>& c_X_b, const Transform<S>& b_X_a) {
  Transform<T> out;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      out.E(i, j) = c_X_b.E(i, 0) * b_X_a.E(0, j) + c_X_b.E(i, 1) * b_X_a.E(1, j) +
                    c_X_b.E(i, 2) * b_X_a.E(2, j);
  for (int i = 0; i < 3; ++i)
    out.r(i) = b_X_a.r(i) + b_X_a.E(0, i) * c_X_b.r(0) + b_X_a.E(1, i) * c_X_b.r(1) +
               b_X_a.E(2, i) * c_X_b.r(2);
  return out;
}

// Rotation matrix E for a frame rotated by angle about unit axis a: the coordinate transform from
// parent to the rotated frame, i.e. the transpose of the Rodrigues rotation (RBDA eq. 2.20).
template <class T, class S>
Mat3<T> rotationCoordinates(const Vec3<S>& a, const T& angle) {
  using std::cos;
  using std::sin;
  const T c = cos(angle), s = sin(angle), one_c = T(1) - c;
  Mat3<T> R;
  R(0, 0) = c + a.x() * a.x() * one_c;
  R(0, 1) = a.x() * a.y() * one_c - a.z() * s;
  R(0, 2) = a.x() * a.z() * one_c + a.y() * s;
  R(1, 0) = a.y() * a.x() * one_c + a.z() * s;
  R(1, 1) = c + a.y() * a.y() * one_c;
  R(1, 2) = a.y() * a.z() * one_c - a.x() * s;
  R(2, 0) = a.z() * a.x() * one_c - a.y() * s;
  R(2, 1) = a.z() * a.y() * one_c + a.x() * s;
  R(2, 2) = c + a.z() * a.z() * one_c;
  return R.transpose();
}

// Rigid-body spatial inertia about a frame origin: mass m, first moment h = m c, and rotational
// inertia Ibar about the origin (RBDA eq. 2.63): I = [Ibar, h x; -h x, m 1].
template <class S>
struct Inertia {
  S mass = S(0);
  Vec3<S> h = Vec3<S>::Zero();
  Mat3<S> Ibar = Mat3<S>::Zero();

  // From mass, centre of mass c and rotational inertia Ic about the centre of mass
  // (parallel-axis theorem, RBDA eq. 2.63).
  static Inertia fromMassCom(const S& m, const Vec3<S>& c, const Mat3<S>& Ic) {
    Inertia I;
    I.mass = m;
    I.h = m * c;
    I.Ibar = Ic + m * (c.dot(c) * Mat3<S>::Identity() - c * c.transpose());
    return I;
  }
  Vec3<S> com() const { return mass > S(0) ? Vec3<S>(h / mass) : Vec3<S>::Zero(); }
  Mat3<S> inertiaAboutCom() const {
    const Vec3<S> c = com();
    return Ibar - mass * (c.dot(c) * Mat3<S>::Identity() - c * c.transpose());
  }
  // The same inertia expressed in frame A, given the transform B_X_A from A to this (B) frame.
  // RBDA eq. 2.66: I_A = X^T I_B X, done through the centre of mass to stay exact.
  Inertia expressedInParent(const Transform<S>& b_X_a) const {
    const Vec3<S> cA = b_X_a.inverseTransformPoint(com());
    const Mat3<S> IcA = b_X_a.E.transpose() * inertiaAboutCom() * b_X_a.E;
    return fromMassCom(mass, cA, IcA);
  }
  Inertia operator+(const Inertia& o) const {
    Inertia I;
    I.mass = mass + o.mass;
    I.h = h + o.h;
    I.Ibar = Ibar + o.Ibar;
    return I;
  }
  Mat6<S> matrix() const {
    Mat6<S> M;
    M.template topLeftCorner<3, 3>() = Ibar;
    M.template topRightCorner<3, 3>() = skew(h);
    M.template bottomLeftCorner<3, 3>() = -skew(h);
    M.template bottomRightCorner<3, 3>() = mass * Mat3<S>::Identity();
    return M;
  }
  template <class U>
  Inertia<U> cast() const {
    Inertia<U> I;
    I.mass = U(mass);
    I.h = h.template cast<U>();
    I.Ibar = Ibar.template cast<U>();
    return I;
  }
};

// I * v for a constant inertia and a variable motion (RBDA eq. 2.63 applied).
template <class T, class S>
Force<T> multiply(const Inertia<S>& I, const Motion<T>& v) {
  Force<T> f;
  for (int i = 0; i < 3; ++i)
    f.ang(i) = I.Ibar(i, 0) * v.ang(0) + I.Ibar(i, 1) * v.ang(1) + I.Ibar(i, 2) * v.ang(2);
  f.ang += cross3<T>(I.h, v.lin);
  f.lin = v.lin * I.mass - cross3<T>(I.h, v.ang);
  return f;
}

}  // namespace spacetime
