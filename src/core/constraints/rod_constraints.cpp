// The direct solve of a Cosserat rod's constraints (rod_constraints.h).
#include "pbd_cloth/constraints/rod_constraints.h"

#include <Eigen/LU>
#include <cmath>

namespace pbd_cloth {

namespace {

Eigen::Matrix3d cross(const Vec3& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// 1 / stiffness, 0 for an infinitely stiff one.
double compliance(double stiffness) { return std::isinf(stiffness) ? 0.0 : 1.0 / stiffness; }

}  // namespace

void RodSolver::prepare(int segments) {
  diagonal_.resize(segments);
  upper_.resize(segments);
  rhs_.resize(segments);
  frame_.resize(segments);
  inverse_inertia_.resize(segments);
  turn_.resize(segments);
}

void RodSolver::solve(Rod& rod, double h) {
  const int n = rod.segments();
  if (n == 0) return;
  if (static_cast<int>(diagonal_.size()) < n) prepare(n);
  const double inv_h2 = 1.0 / (h * h);
  for (int s = 0; s < n; ++s) {
    frame_[s] = rod.orientation[s].toRotationMatrix();
    const Vec3 w(rod.inverse_inertia_bend[s], rod.inverse_inertia_bend[s],
                 rod.inverse_inertia_twist[s]);
    inverse_inertia_[s] = frame_[s] * w.asDiagonal() * frame_[s].transpose();
  }
  // The blocks and the right-hand side -C - alpha~ lambda.
  for (int s = 0; s < n; ++s) {
    Matrix6& d = diagonal_[s];
    Matrix6& u = upper_[s];
    d.setZero();
    u.setZero();
    const double l = rod.rest_length[s];
    const double wi = rod.inverse_mass[s], wj = rod.inverse_mass[s + 1];
    const Vec3 d3 = frame_[s].col(2);
    const Eigen::Matrix3d d3x = cross(d3);
    const Eigen::Matrix3d& w_s = inverse_inertia_[s];
    // Stretch-shear of segment s.
    const Eigen::Matrix3d along = d3 * d3.transpose();
    const Eigen::Matrix3d alpha_s =
        (inv_h2 / l) * (compliance(rod.stiffness.stretch) * along +
                        compliance(rod.stiffness.shear) * (Eigen::Matrix3d::Identity() - along));
    d.topLeftCorner<3, 3>() =
        ((wi + wj) / (l * l)) * Eigen::Matrix3d::Identity() + d3x * w_s * d3x.transpose() + alpha_s;
    const Vec3 c_s = (rod.position[s + 1] - rod.position[s]) / l - d3;
    rhs_[s].head<3>() = -c_s - alpha_s * rod.stretch_shear_lambda[s];
    if (wi + wj == 0.0 && alpha_s.isZero(0.0) && !w_s.isZero(0.0)) {
      // Both ends held and the rope inextensible: nothing changes the stretch along d3 (the
      // segment's turn only moves d3 across itself). That row is left out: unit diagonal, nothing
      // on the right, and no coupling (the others reach this block across d3 only).
      d.topLeftCorner<3, 3>() += along;
      rhs_[s].head<3>() -= along * rhs_[s].head<3>();
    }
    if (s + 1 < n) {
      const double l_next = rod.rest_length[s + 1];
      const double lbar = 0.5 * (l + l_next);
      const Eigen::Matrix3d& w_next = inverse_inertia_[s + 1];
      const Eigen::Matrix3d& r_s = frame_[s];
      const Eigen::Matrix3d d3x_next = cross(frame_[s + 1].col(2));
      // Bend-twist of joint s: gradient -R_s^T / lbar on theta_s, R_s^T / lbar on theta_{s+1}.
      const Vec3 k(rod.stiffness.bend, rod.stiffness.bend, rod.stiffness.twist);
      Eigen::Matrix3d alpha_b = Eigen::Matrix3d::Zero();
      for (int axis = 0; axis < 3; ++axis)
        alpha_b(axis, axis) = inv_h2 * compliance(k[axis]) / lbar;
      d.bottomRightCorner<3, 3>() =
          r_s.transpose() * (w_s + w_next) * r_s / (lbar * lbar) + alpha_b;
      // Stretch-shear s with bend-twist s (both move theta_s).
      d.topRightCorner<3, 3>() = d3x * w_s * (-r_s / lbar);
      d.bottomLeftCorner<3, 3>() = d.topRightCorner<3, 3>().transpose();
      const Vec3 c_b = darbouxVector(rod, s) - rod.rest_darboux[s];
      rhs_[s].tail<3>() = -c_b - alpha_b * rod.bend_twist_lambda[s];
      // Coupling to unit s + 1: stretch-shear s and s + 1 share x_{s+1}; bend-twist s shares
      // theta_{s+1} with stretch-shear s + 1 and bend-twist s + 1.
      u.topLeftCorner<3, 3>() = (-wj / (l * l_next)) * Eigen::Matrix3d::Identity();
      u.bottomLeftCorner<3, 3>() = (r_s.transpose() / lbar) * w_next * d3x_next.transpose();
      if (s + 2 < n) {
        const double lbar_next = 0.5 * (l_next + rod.rest_length[s + 2]);
        u.bottomRightCorner<3, 3>() =
            (r_s.transpose() / lbar) * w_next * (-frame_[s + 1] / lbar_next);
      }
    } else {
      d.bottomRightCorner<3, 3>().setIdentity();
      rhs_[s].tail<3>().setZero();
    }
    // A constraint on kinematic ends only (no free degree of freedom, infinitely stiff): nothing
    // to solve; its rows become identity with nothing on the right.
    for (int row = 0; row < 6; ++row) {
      if (d(row, row) <= 0.0) {
        d.row(row).setZero();
        d.col(row).setZero();
        d(row, row) = 1.0;
        rhs_[s][row] = 0.0;
        if (s > 0) upper_[s - 1].col(row).setZero();
        u.row(row).setZero();
      }
    }
  }
  // Block tridiagonal elimination (the lower blocks are the upper ones transposed): D'_s = D_s -
  // U_{s-1}^T D'_{s-1}^-1 U_{s-1}; then back substitution. upper_[s] becomes D'_s^-1 U_s.
  Matrix6 previous_inverse_upper = Matrix6::Zero();  // D'_{s-1}^-1 U_{s-1}
  Matrix6 previous_upper = Matrix6::Zero();          // U_{s-1}
  for (int s = 0; s < n; ++s) {
    if (s > 0) {
      diagonal_[s] -= previous_upper.transpose() * previous_inverse_upper;
      rhs_[s] -= previous_upper.transpose() * rhs_[s - 1];
    }
    const Eigen::PartialPivLU<Matrix6> lu(diagonal_[s]);
    rhs_[s] = lu.solve(rhs_[s]);  // D'_s^-1 r'_s
    previous_upper = upper_[s];
    upper_[s] = lu.solve(upper_[s]);  // D'_s^-1 U_s
    previous_inverse_upper = upper_[s];
  }
  for (int s = n - 2; s >= 0; --s) rhs_[s] -= upper_[s] * rhs_[s + 1];
  // x += W J^T dlambda.
  for (int s = 0; s < n; ++s) turn_[s].setZero();
  for (int s = 0; s < n; ++s) {
    const double l = rod.rest_length[s];
    const Vec3 dlambda_s = rhs_[s].head<3>();
    rod.stretch_shear_lambda[s] += dlambda_s;
    rod.position[s] -= (rod.inverse_mass[s] / l) * dlambda_s;
    rod.position[s + 1] += (rod.inverse_mass[s + 1] / l) * dlambda_s;
    turn_[s] += inverse_inertia_[s] * dlambda_s.cross(frame_[s].col(2));
    if (s + 1 < n) {
      const double lbar = 0.5 * (l + rod.rest_length[s + 1]);
      const Vec3 dlambda_b = rhs_[s].tail<3>();
      rod.bend_twist_lambda[s] += dlambda_b;
      const Vec3 world = frame_[s] * dlambda_b / lbar;
      turn_[s] -= inverse_inertia_[s] * world;
      turn_[s + 1] += inverse_inertia_[s + 1] * world;
    }
  }
  for (int s = 0; s < n; ++s) {
    if (turn_[s].squaredNorm() > 0.0) applySmallRotation(rod.orientation[s], turn_[s]);
  }
}

Vec3 rodJointMoment(const Rod& rod, int k) {
  const Vec3 c = darbouxVector(rod, k) - rod.rest_darboux[k];
  return Vec3(rod.stiffness.bend * c.x(), rod.stiffness.bend * c.y(), rod.stiffness.twist * c.z());
}

}  // namespace pbd_cloth
