#pragma once
// A KKT matrix as Ipopt's ma27 slot receives it: 1-based triplets of either triangle, duplicates
// summed; shared by the slot's tests (dense, condensed, sparse).
#include <Eigen/Core>
#include <vector>

namespace flatsos::test {

struct KktTriplets {
  int n = 0;
  std::vector<int> irn, icn;  // 1-based
  std::vector<double> values;
  void add(int i, int j, double v) {  // a(i, j), 0-based, in the triangle given
    irn.push_back(i + 1);
    icn.push_back(j + 1);
    values.push_back(v);
  }
  /// The symmetric matrix the triplets describe.
  Eigen::MatrixXd dense() const {
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
    for (std::size_t e = 0; e < values.size(); ++e) {
      const int i = irn[e] - 1, j = icn[e] - 1;
      a(i, j) += values[e];
      if (i != j) a(j, i) += values[e];
    }
    return a;
  }
};

}  // namespace flatsos::test
