// Geometry on an ellipsoid as OpenSim's WrapEllipsoid does it (findClosestPoint after Eberly,
// Graphics Gems IV 1994; calcTangentPoint; CalcDistanceOnEllipsoid). Iteration counts,
// tolerances and step rules are OpenSim's, so that lengths agree with it.

#include "ellipsoid_geometry.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/LU>

namespace flatsos::plugin::ellipsoid {

namespace {

using wrap_math::kPi;
using wrap_math::unit_or_zero;

constexpr double kRoundoff = 2e-13;  // OpenSim's ROUNDOFF_ERROR

bool near_zero(double v) { return std::abs(v) <= kRoundoff; }

// The point (x, y) of the ellipse (x/a)^2 + (y/b)^2 = 1 closest to (u, v).
void closest_on_ellipse(double a, double b, double u, double v, double& x, double& y) {
  const double a2 = a * a, b2 = b * b, a2u2 = a2 * u * u, b2v2 = b2 * v * v;
  const bool near_x = near_zero(u), near_y = near_zero(v);
  if (near_x && near_y) {
    if (a < b) {
      x = u < 0.0 ? -a : a, y = v;
    } else {
      x = u, y = v < 0.0 ? -b : b;
    }
    return;
  }
  if (near_x) {
    if (a >= b || std::abs(v) >= b - a2 / b) {
      x = u, y = v >= 0.0 ? b : -b;
    } else {
      y = b2 * v / (b2 - a2);
      const double ydb = y / b;
      x = a * std::sqrt(std::abs(1.0 - ydb * ydb));
    }
    return;
  }
  if (near_y) {
    if (b >= a || std::abs(u) >= a - b2 / a) {
      x = u >= 0.0 ? a : -a, y = v;
    } else {
      x = a2 * u / (a2 - b2);
      const double xda = x / a;
      y = b * std::sqrt(std::abs(1.0 - xda * xda));
    }
    return;
  }
  double t = (u / a) * (u / a) + (v / b) * (v / b) < 1.0 ? 0.0 : std::max(a, b) * std::sqrt(u * u + v * v);
  double P = 0.0, Q = 0.0;
  for (int i = 0; i < 64; ++i) {
    P = t + a2, Q = t + b2;
    const double f = P * P * Q * Q - a2u2 * Q * Q - b2v2 * P * P;
    if (std::abs(f) < 1e-9) break;
    t -= f / (2.0 * (P * Q * (P + Q) - a2u2 * Q - b2v2 * P));
  }
  x = a2 * u / P, y = b2 * v / Q;
}

Vec3 closest_in_3d(const Vec3& a, const Vec3& p) {
  const Vec3 a2 = a.cwiseProduct(a);
  const double a2u2 = a2[0] * p[0] * p[0], b2v2 = a2[1] * p[1] * p[1], c2w2 = a2[2] * p[2] * p[2];
  double t = p.cwiseQuotient(a).squaredNorm() < 1.0 ? 0.0 : a.maxCoeff() * p.norm();
  Vec3 last = Vec3::Zero();
  for (int i = 0; i < 64; ++i) {
    const double P = t + a2[0], Q = t + a2[1], R = t + a2[2];
    last = Vec3(a2[0] * p[0] / P, a2[1] * p[1] / Q, a2[2] * p[2] / R);
    const double f = P * P * Q * Q * R * R - a2u2 * Q * Q * R * R - b2v2 * P * P * R * R - c2w2 * P * P * Q * Q;
    if (std::abs(f) < 1e-9) return last;
    const double PQ = P * Q, PR = P * R, QR = Q * R;
    const double fp = 2.0 * (PQ * R * (QR + PR + PQ) - a2u2 * QR * (Q + R) - b2v2 * PR * (P + R) - c2w2 * PQ * (P + Q));
    t -= f / fp;
  }
  return last;
}

// OpenSim's four residuals of calcTangentPoint: in the plane, on the surface, and the tangent
// plane at r (n . x + d = 0, n the scaled normal) through r and through p.
struct Residuals {
  double e[4];
  double squared() const { return e[0] * e[0] + e[1] * e[1] + e[2] * e[2] + e[3] * e[3]; }
};
Residuals residuals(const Vec3& r, double d, const Vec3& p, const Vec3& a, const Vec3& vs, double vs4) {
  Residuals out;
  out.e[0] = vs.dot(r) + vs4;
  out.e[1] = -1.0;
  double normal_r = 0.0, normal_p = 0.0;
  for (int i = 0; i < 3; ++i) {
    out.e[1] += (r[i] / a[i]) * (r[i] / a[i]);
    const double normal = 2.0 * r[i] / (a[i] * a[i]);
    normal_r += normal * r[i];
    normal_p += normal * p[i];
  }
  out.e[2] = normal_r + d;
  out.e[3] = normal_p + d;
  return out;
}

}  // namespace

Vec3 closest_point(const Vec3& a, const Vec3& p, int special_axis) {
  if (special_axis < 0) {
    double narrowest = INFINITY;
    for (int i = 0; i < 3; ++i) {
      if (!near_zero(p[i])) continue;
      const double radii_sum = a.sum() - a[i];
      if (narrowest > radii_sum) special_axis = i, narrowest = radii_sum;
    }
  }
  Vec3 out = p;
  switch (special_axis) {
    case 0: closest_on_ellipse(a[1], a[2], p[1], p[2], out[1], out[2]); return out;
    case 1: closest_on_ellipse(a[2], a[0], p[2], p[0], out[2], out[0]); return out;
    case 2: closest_on_ellipse(a[0], a[1], p[0], p[1], out[0], out[1]); return out;
    default: return closest_in_3d(a, p);
  }
}

void tangent_point(double p_level, const Vec3& p, const Vec3& a, const Vec3& vs, double vs4, Vec3& r) {
  if (std::abs(p_level) < 1e-4) {
    r = p;
    return;
  }
  const Vec3 a2 = a.cwiseProduct(a);
  double d = 0.0;
  for (int i = 0; i < 3; ++i) d -= 2.0 * r[i] / a2[i] * r[i];
  double ssq = residuals(r, d, p, a, vs, vs4).squared(), ssq_before = ssq;
  double damping = 0.01;
  for (int outer = 0; ssq > 1e-8 && outer < 50; ++outer) {
    // Jacobian (parameters r, d by rows; residuals by columns), as OpenSim builds it.
    Eigen::Matrix4d J;
    for (int i = 0; i < 3; ++i)
      J.row(i) << vs[i], 2.0 * r[i] / a2[i], 2.0 * (2.0 * r[i]) / a2[i], 2.0 * p[i] / a2[i];
    J.row(3) << 0.0, 0.0, 1.0, 1.0;
    const double along_p = unit_or_zero(p - r).dot(unit_or_zero(p));
    const double shrink = along_p > 0.1 ? 1.0 - std::pow(along_p, 100) : 1.0;
    const Residuals e = residuals(r, d, p, a, vs, vs4);
    const Eigen::Vector4d gradient = -(J * Eigen::Vector4d(e.e[0], e.e[1], e.e[2], e.e[3]));
    Eigen::Matrix4d normal_matrix = J * J.transpose();
    const Eigen::Vector4d diagonal = normal_matrix.diagonal();
    Eigen::Vector4d step = Eigen::Vector4d::Zero();
    // Raise the damping until a step lowers the residual (each trial step adds to the last).
    for (int trial = 0; ssq >= ssq_before && trial < 1000; ++trial) {
      normal_matrix.diagonal() = diagonal * (1.0 + damping);
      step = shrink * (normal_matrix.inverse() * gradient) / 16.0;
      r += step.head<3>();
      d += step[3];
      ssq_before = ssq;
      ssq = residuals(r, d, p, a, vs, vs4).squared();
      damping *= 4.0;
    }
    damping /= 8.0;
    // Then double the step while it keeps lowering the residual, and take back the last one.
    double factor = 0.5;
    for (int trial = 0; ssq <= ssq_before && trial < 1000; ++trial) {
      factor *= 2.0;
      r += step.head<3>() * factor;
      d += step[3] * factor;
      ssq_before = ssq;
      ssq = residuals(r, d, p, a, vs, vs4).squared();
    }
    r -= step.head<3>() * factor;
    d -= step[3] * factor;
    ssq = residuals(r, d, p, a, vs, vs4).squared();
    ssq_before = ssq;
  }
}

Polyline surface_polyline(const Vec3& r1, const Vec3& r2, const Vec3& a, const Vec3& vs, double vs4, bool far_side, double factor,
                          std::vector<Vec3>* points) {
  Polyline out;
  const double chord_m = (r1 - r2).norm() / factor;
  if (points) points->assign({r1, r2});
  if (chord_m < 0.001) {
    out.length = chord_m * factor;
    out.point_count = 2;
    return out;
  }
  const int segments = std::min(static_cast<int>(chord_m / 0.001), 499);
  int most_aligned = 0;
  for (int i = 1; i < 3; ++i)  // the first of equal components, as OpenSim scans
    if (std::abs(vs[i]) > std::abs(vs[most_aligned])) most_aligned = i;
  Vec3 a0 = Vec3::Zero();
  a0[most_aligned] = -vs4 / vs[most_aligned];
  const Vec3 from1 = unit_or_zero(r1 - a0), from2 = unit_or_zero(r2 - a0);
  const double angle = std::acos(from1.dot(from2));
  const double step = far_side ? -(2.0 * kPi - angle) / segments : angle / segments;
  const Vec3 normal = unit_or_zero(from1.cross(from2));
  const Vec3 in_plane = normal.cross(from1);
  const Vec3 f2 = a0.cwiseQuotient(a);
  if (points) points->pop_back();
  Vec3 previous = r1;
  for (int i = 0; i + 1 < segments; ++i) {
    const double phi = (i + 1) * step;
    const Vec3 ray = std::cos(phi) * from1 + std::sin(phi) * in_plane;
    const Vec3 f1 = ray.cwiseQuotient(a);
    const double qa = f1.dot(f1), qb = 2.0 * f1.dot(f2), qc = f2.dot(f2) - 1.0;
    const Vec3 s = a0 + (-qb + std::sqrt(qb * qb - 4.0 * qa * qc)) / (2.0 * qa) * ray;
    if (i == 0) out.first_interior = s;
    out.last_interior = s;
    out.length += (s - previous).norm();
    previous = s;
    if (points) points->push_back(s);
  }
  out.length += (r2 - previous).norm();
  if (points) points->push_back(r2);
  out.point_count = segments + 1;
  return out;
}

}  // namespace flatsos::plugin::ellipsoid
