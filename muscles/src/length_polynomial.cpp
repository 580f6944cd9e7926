#include "flatsos/muscles/length_polynomial.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>

namespace flatsos::muscles {

namespace {

constexpr long kCountCap = 1000000000L;

void append_exponents(int order_left, std::vector<int>& prefix, int dimension, std::vector<std::vector<int>>& out) {
  if (static_cast<int>(prefix.size()) == dimension) {
    out.push_back(prefix);
    return;
  }
  for (int e = 0; e <= order_left; ++e) {
    prefix.push_back(e);
    append_exponents(order_left - e, prefix, dimension, out);
    prefix.pop_back();
  }
}

// a <- a * b for truncated Taylor series of `count` coefficients.
void multiply_series(double* a, const double* b, int count) {
  for (int j = count - 1; j >= 0; --j) {
    double s = 0.0;
    for (int i = 0; i <= j; ++i) s += a[i] * b[j - i];
    a[j] = s;
  }
}

}  // namespace

namespace {
// The polynomial of `dimension` arguments and `order` made of the terms (coefficients, and
// exponents `from_dimension` per term) each mapped by `map(exponents, coefficient)`: it edits the
// exponents into the new polynomial's and returns the term's coefficient there (0: none).
template <class Map>
LengthPolynomial collect_terms(const std::vector<double>& coefficients, const std::vector<int>& exponents,
                               int from_dimension, int dimension, int order, Map map) {
  const auto table = LengthPolynomial::termExponents(dimension, order);
  std::map<std::vector<int>, std::size_t> position;
  for (std::size_t t = 0; t < table.size(); ++t) position[table[t]] = t;
  std::vector<double> c(table.size(), 0.0);
  for (std::size_t t = 0; t < coefficients.size(); ++t) {
    std::vector<int> e(exponents.begin() + static_cast<long>(t * from_dimension),
                       exponents.begin() + static_cast<long>((t + 1) * from_dimension));
    const double value = map(e, coefficients[t]);
    if (value != 0.0) c[position.at(e)] += value;
  }
  return LengthPolynomial(dimension, order, std::move(c));
}
}  // namespace

long LengthPolynomial::termCount(int dimension, int order) {
  if (dimension < 0 || order < 0) return 0;
  // binom(d + o, o) built as a product of exact binomials: c_i = c_{i-1} (d + i) / i.
  long c = 1;
  for (int i = 1; i <= order; ++i) {
    c = c * (dimension + i) / i;
    if (c > kCountCap) return kCountCap;
  }
  return c;
}

std::vector<std::vector<int>> LengthPolynomial::termExponents(int dimension, int order) {
  std::vector<std::vector<int>> out;
  if (dimension < 0 || order < 0 || termCount(dimension, order) >= kCountCap) return out;
  std::vector<int> prefix;
  append_exponents(order, prefix, dimension, out);
  return out;
}

LengthPolynomial::LengthPolynomial(int dimension, int order, std::vector<double> coefficients)
    : dimension_(dimension), order_(order), coefficients_(std::move(coefficients)) {
  if (dimension < 0 || dimension > kMaxDimension)
    throw std::invalid_argument("dimension " + std::to_string(dimension) + " is outside [0, " +
                                std::to_string(kMaxDimension) + "]");
  if (order < 0) throw std::invalid_argument("order " + std::to_string(order) + " is negative");
  const long expected = termCount(dimension, order);
  if (static_cast<long>(coefficients_.size()) != expected)
    throw std::invalid_argument("dimension " + std::to_string(dimension) + " and order " + std::to_string(order) +
                                " need " + std::to_string(expected) + " coefficients, got " +
                                std::to_string(coefficients_.size()));
  for (std::size_t i = 0; i < coefficients_.size(); ++i)
    if (!std::isfinite(coefficients_[i]))
      throw std::invalid_argument("coefficient " + std::to_string(i) + " is not finite");
  const auto exponents = termExponents(dimension, order);
  for (std::size_t t = 0; t < exponents.size(); ++t) {
    if (coefficients_[t] == 0.0) continue;
    term_coefficient_.push_back(coefficients_[t]);
    term_exponents_.insert(term_exponents_.end(), exponents[t].begin(), exponents[t].end());
  }
  std::vector<int> largest(static_cast<std::size_t>(dimension_), 0);
  for (std::size_t i = 0; i < term_exponents_.size(); ++i) {
    int& l = largest[i % static_cast<std::size_t>(dimension_)];
    l = std::max(l, term_exponents_[i]);
  }
  power_row_.assign(1, 0);
  for (int e : largest) power_row_.push_back(power_row_.back() + e + 1);
}

bool LengthPolynomial::independentOf(int k) const {
  if (k < 0 || k >= dimension_) return true;
  for (std::size_t t = 0; t < term_coefficient_.size(); ++t)
    if (term_exponents_[t * dimension_ + k] > 0) return false;
  return true;
}

double LengthPolynomial::value(const double* x) const {
  double sum = 0.0;
  for (std::size_t t = 0; t < term_coefficient_.size(); ++t) {
    double term = term_coefficient_[t];
    const int* e = term_exponents_.data() + t * dimension_;
    for (int k = 0; k < dimension_; ++k)
      for (int p = 0; p < e[k]; ++p) term *= x[k];
    sum += term;
  }
  return sum;
}

LengthPolynomial LengthPolynomial::derivative(int k) const {
  if (k < 0 || k >= dimension_)
    throw std::invalid_argument("derivative with respect to argument " + std::to_string(k) + " of a polynomial of " +
                                std::to_string(dimension_) + " arguments");
  return collect_terms(term_coefficient_, term_exponents_, dimension_, dimension_, order_ > 0 ? order_ - 1 : 0,
                       [k](std::vector<int>& e, double c) {
                         if (e[k] == 0) return 0.0;
                         const double factor = e[k];
                         --e[k];
                         return factor * c;
                       });
}

LengthPolynomial LengthPolynomial::withArgumentHeld(int k, double value) const {
  if (k < 0 || k >= dimension_)
    throw std::invalid_argument("holding argument " + std::to_string(k) + " of a polynomial of " + std::to_string(dimension_) +
                                " arguments");
  if (!std::isfinite(value)) throw std::invalid_argument("holding argument " + std::to_string(k) + " at a value that is not finite");
  return collect_terms(term_coefficient_, term_exponents_, dimension_, dimension_ - 1, order_,
                       [k, value](std::vector<int>& e, double c) {
                         for (int p = 0; p < e[k]; ++p) c *= value;
                         e.erase(e.begin() + k);
                         return c;
                       });
}

void LengthPolynomial::timeDerivatives(const double* x_jet, int count, double* out) const {
  if (count < 1 || count > kMaxJetCount)
    throw std::invalid_argument("time derivatives: count " + std::to_string(count) + " is outside [1, " +
                                std::to_string(kMaxJetCount) + "]");
  // Taylor coefficients x_k(t + s) = sum_j X[k][j] s^j, X[k][j] = d^j x_k / dt^j / j!.
  double X[kMaxDimension][kMaxJetCount];
  double factorial[kMaxJetCount];
  factorial[0] = 1.0;
  for (int j = 1; j < count; ++j) factorial[j] = factorial[j - 1] * j;
  for (int k = 0; k < dimension_; ++k)
    for (int j = 0; j < count; ++j) X[k][j] = x_jet[j * dimension_ + k] / factorial[j];
  double sum[kMaxJetCount] = {};
  double term[kMaxJetCount];
  if (power_row_.back() <= kMaxPowerRows) {
    // Each term: its coefficient times one series product per argument in it, from the table
    // of powers (a univariate polynomial of degree d: d products in all, not d^2 / 2).
    double power[kMaxPowerRows][kMaxJetCount];
    for (int k = 0; k < dimension_; ++k) {
      const int first = power_row_[static_cast<std::size_t>(k)], end = power_row_[static_cast<std::size_t>(k) + 1];
      power[first][0] = 1.0;
      for (int j = 1; j < count; ++j) power[first][j] = 0.0;
      for (int row = first + 1; row < end; ++row) {
        std::copy_n(power[row - 1], count, power[row]);
        multiply_series(power[row], X[k], count);
      }
    }
    for (std::size_t t = 0; t < term_coefficient_.size(); ++t) {
      const int* e = term_exponents_.data() + t * dimension_;
      bool started = false;
      for (int k = 0; k < dimension_; ++k) {
        if (e[k] == 0) continue;
        const double* p = power[power_row_[static_cast<std::size_t>(k)] + e[k]];
        if (started) multiply_series(term, p, count);
        else std::copy_n(p, count, term);
        started = true;
      }
      if (!started) sum[0] += term_coefficient_[t];
      else
        for (int j = 0; j < count; ++j) sum[j] += term_coefficient_[t] * term[j];
    }
  } else {
    // Exponents too large for the table: one series product per unit of exponent.
    for (std::size_t t = 0; t < term_coefficient_.size(); ++t) {
      term[0] = term_coefficient_[t];
      for (int j = 1; j < count; ++j) term[j] = 0.0;
      const int* e = term_exponents_.data() + t * dimension_;
      for (int k = 0; k < dimension_; ++k)
        for (int p = 0; p < e[k]; ++p) multiply_series(term, X[k], count);
      for (int j = 0; j < count; ++j) sum[j] += term[j];
    }
  }
  for (int j = 0; j < count; ++j) out[j] = sum[j] * factorial[j];
}

}  // namespace flatsos::muscles
