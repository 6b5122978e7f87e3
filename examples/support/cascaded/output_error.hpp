#pragma once

// The output-error fit of the Cascaded Tanks model on the estimation set, without any filter: the
// parameters and x₁(0) that make the free run fit yEst best (least squares, Levenberg–Marquardt from
// several deterministic starts). `mjukf_cascaded_tanks terms` fits each structure with it, to measure
// what each term of the model adds (docs/real-data.md).

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cascaded/identification.hpp"

namespace mjukf::cascaded {

/// A model structure: its terms and the parameters it fits (the others stay at the first guess).
struct Structure {
  std::string name;
  Model::Terms terms;
  std::vector<int> free;  ///< indices into θ
};

/// The structures of docs/real-data.md, each adding one term to the one before.
inline std::vector<Structure> structures() {
  using M = Model;
  std::vector<Structure> s;
  M::Terms t{false, false, false, false};
  std::vector<int> free{M::kLnK1, M::kLnK3, M::kLnK4};
  s.push_back({"Torricelli (k1, k3, k4)", t, free});
  t.upperOverflow = true;
  free.insert(free.end(), {M::kLnHmax, M::kLnK5});
  s.push_back({"+ upper-tank overflow (h_max, k5)", t, free});
  t.lowerFull = true;
  s.push_back({"+ lower tank full at 10 V", t, free});
  t.freeExponent = true;
  free.push_back(M::kLnAlpha);
  s.push_back({"+ free exponent of the lower outflow (alpha)", t, free});
  t.sensorOffset = true;
  free.push_back(M::kOffset);
  s.push_back({"+ sensor offset (c): the model the filters use", t, free});
  return s;
}

/// What the fit found.
struct OutputErrorFit {
  Param theta;
  double upperLevel0 = 0;  ///< x₁(0) of the estimation set
  double estimationRms = std::numeric_limits<double>::infinity();
};

namespace detail {

inline Eigen::VectorXd residuals(const Model& model, const Benchmark& b, const Param& theta, double x10) {
  const Series y = simulate(model, theta, b.uEst, State(x10, std::max(b.yEst[0] - model.physical(theta).offset, 0.0)),
                            b.samplePeriod);
  Eigen::VectorXd r(y.size());
  for (std::size_t k = 0; k < y.size(); ++k) r(long(k)) = y[k] - b.yEst[k];
  return r;
}

}  // namespace detail

/// Levenberg–Marquardt on v = (θ's free components, x₁(0)) from each of `starts` starts spread
/// deterministically around the first guess; the best fit.
inline OutputErrorFit fitOutputError(const Model& model, const Benchmark& b, const std::vector<int>& free,
                                     int starts = 12, const Param* from = nullptr) {
  const Param theta0 = from ? *from : firstGuess(b);
  const int n = int(free.size()) + 1;
  const auto unpack = [&](const Eigen::VectorXd& v) {
    Param theta = theta0;
    for (int i = 0; i + 1 < n; ++i) theta(free[std::size_t(i)]) = v(i);
    return theta;
  };
  OutputErrorFit best;
  for (int start = 0; start < starts; ++start) {
    Eigen::VectorXd v(n);
    for (int i = 0; i + 1 < n; ++i) {
      // A low-discrepancy spread: each start moves each log-parameter within ± ln 2 (c within ± 0.5 V).
      const double spread = std::fmod(0.618034 * (start + 1) * (i + 2) + 0.5, 1.0) * 2 - 1;
      v(i) = theta0(free[std::size_t(i)]) +
             (start == 0 ? 0.0 : spread * (free[std::size_t(i)] == Model::kOffset ? 0.5 : 0.69));
    }
    v(n - 1) = 2.0 + 8.0 * std::fmod(0.381966 * start, 1.0);
    Eigen::VectorXd r = detail::residuals(model, b, unpack(v), v(n - 1));
    double cost = r.squaredNorm(), damping = 1e-2;
    for (int iteration = 0; iteration < 200 && std::isfinite(cost); ++iteration) {
      Eigen::MatrixXd jacobian(r.size(), n);
      for (int j = 0; j < n; ++j) {
        Eigen::VectorXd w = v;
        const double step = 1e-6 * std::max(1.0, std::abs(v(j)));
        w(j) += step;
        jacobian.col(j) = (detail::residuals(model, b, unpack(w), w(n - 1)) - r) / step;
      }
      const Eigen::MatrixXd a = jacobian.transpose() * jacobian;
      const Eigen::VectorXd g = jacobian.transpose() * r;
      bool improved = false, converged = false;
      for (int attempt = 0; attempt < 10 && !improved; ++attempt) {
        Eigen::MatrixXd damped = a;
        damped.diagonal() += damping * a.diagonal().cwiseMax(1e-12);
        const Eigen::VectorXd w = v - damped.ldlt().solve(g);
        const Eigen::VectorXd rw = detail::residuals(model, b, unpack(w), w(n - 1));
        const double c = rw.squaredNorm();
        if (std::isfinite(c) && c < cost) {
          converged = cost - c < 1e-10 * cost;
          v = w, r = rw, cost = c, improved = true;
          damping = std::max(damping / 3, 1e-9);
        } else {
          damping *= 4;
        }
      }
      if (!improved || converged) break;
    }
    const double rms = std::sqrt(cost / double(r.size()));
    if (rms < best.estimationRms) best = {unpack(v), v(n - 1), rms};
  }
  return best;
}

}  // namespace mjukf::cascaded
