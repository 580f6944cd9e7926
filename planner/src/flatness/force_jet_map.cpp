// ForceJetMap's products: the tendon-force jet from the torque and flat-output jets, and C_Y's
// rates along the motion (flat_outputs.hpp).
#include "flatsos/planner/flat_outputs.hpp"

namespace flatsos::planner {

void ForceJetMap::mix(Eigen::MatrixXd& v0, Eigen::MatrixXd& v1, Eigen::MatrixXd& v2) const {
  if (!varies()) return;
  v2 += W21 * v1 + W20 * v0;  // before v1 changes
  v1 += W10 * v0;
}

void ForceJetMap::flatOutputColumnRates(Eigen::MatrixXd& CY1, Eigen::MatrixXd& CY2) const {
  if (!varies()) {
    CY1.setZero(CY.rows(), CY.cols());
    CY2.setZero(CY.rows(), CY.cols());
    return;
  }
  // d(C^-1)/dt = -C^-1 (dC/dt) C^-1 with dC/dt = [R1; 0]: dC_Y/dt = -C_tau (R1 C_Y), and again
  // d2C_Y/dt2 = C_tau (2 R1 C_tau R1 C_Y - R2 C_Y).
  const Eigen::MatrixXd r1_cy = R1 * CY;
  CY1.noalias() = -Ctau * r1_cy;
  Eigen::MatrixXd middle = R2 * CY;
  middle.noalias() += 2.0 * R1 * CY1;
  CY2.noalias() = -Ctau * middle;
}

Eigen::MatrixXd ForceJetMap::forceJet(const Eigen::MatrixXd& tau, const Eigen::MatrixXd& Y) const {
  Eigen::MatrixXd v0 = Ctau * tau.col(0) + CY * Y.col(0);
  Eigen::MatrixXd v1 = Ctau * tau.col(1) + CY * Y.col(1);
  Eigen::MatrixXd v2 = Ctau * tau.col(2);
  if (Y.cols() > 2) v2 += CY * Y.col(2);
  mix(v0, v1, v2);
  Eigen::MatrixXd F(Ctau.rows(), 3);
  F << v0, v1, v2;
  return F;
}

}  // namespace flatsos::planner
