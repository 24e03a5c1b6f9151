// Frame-cost prediction (Funkhouser & Sequin 1993, §4.1, linear-sum form) and its calibration by
// regularised recursive least squares with exponential forgetting (information form, ridge toward the
// prior, non-negativity by an active set as in Lawson & Hanson's NNLS, simplified).
#include "scenelod/selection/cost_model.h"

#include <algorithm>
#include <cmath>

namespace scenelod::selection {

namespace {

constexpr size_t kN = kCostTermCount;
// nominal scales used when a prior coefficient is 0 (so a term can still be learnt)
constexpr double kNominal[kN] = {0.5, 2.0e-3, 1.0e-6, 5.0e-7, 1.0e-6, 1.0e-7};

void toArray(const CostCoefficients& c, double* a) {
  a[0] = c.per_frame_ms; a[1] = c.per_object_ms; a[2] = c.per_triangle_ms;
  a[3] = c.per_vertex_ms; a[4] = c.per_line_point_ms; a[5] = c.per_pixel_ms;
}
CostCoefficients fromArray(const double* a) {
  CostCoefficients c;
  c.per_frame_ms = a[0]; c.per_object_ms = a[1]; c.per_triangle_ms = a[2];
  c.per_vertex_ms = a[3]; c.per_line_point_ms = a[4]; c.per_pixel_ms = a[5];
  return c;
}
void toArray(const CostFeatures& f, double* a) {
  a[0] = f.frames; a[1] = f.objects; a[2] = f.triangles; a[3] = f.vertices; a[4] = f.line_points; a[5] = f.pixels;
}

// Solves the symmetric positive definite system restricted to the free indices by Cholesky; x of
// fixed indices is 0. Returns false when a pivot is not positive.
bool choleskySolve(const double* a, const double* b, const bool* free_index, double* x) {
  size_t idx[kN];
  size_t n = 0;
  for (size_t i = 0; i < kN; ++i)
    if (free_index[i]) idx[n++] = i;
  double l[kN * kN] = {};
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j <= i; ++j) {
      double s = a[idx[i] * kN + idx[j]];
      for (size_t k = 0; k < j; ++k) s -= l[i * kN + k] * l[j * kN + k];
      if (i == j) {
        if (!(s > 0.0)) return false;
        l[i * kN + i] = std::sqrt(s);
      } else {
        l[i * kN + j] = s / l[j * kN + j];
      }
    }
  }
  double y[kN] = {};
  for (size_t i = 0; i < n; ++i) {
    double s = b[idx[i]];
    for (size_t k = 0; k < i; ++k) s -= l[i * kN + k] * y[k];
    y[i] = s / l[i * kN + i];
  }
  double z[kN] = {};
  for (size_t ii = n; ii-- > 0;) {
    double s = y[ii];
    for (size_t k = ii + 1; k < n; ++k) s -= l[k * kN + ii] * z[k];
    z[ii] = s / l[ii * kN + ii];
  }
  for (size_t i = 0; i < kN; ++i) x[i] = 0.0;
  for (size_t i = 0; i < n; ++i) x[idx[i]] = z[i];
  return true;
}

}  // namespace

double predictFrameMs(const CostCoefficients& c, const CostFeatures& f) {
  return c.per_frame_ms * f.frames + c.per_object_ms * f.objects + c.per_triangle_ms * f.triangles +
         c.per_vertex_ms * f.vertices + c.per_line_point_ms * f.line_points + c.per_pixel_ms * f.pixels;
}

CostCalibrator::CostCalibrator(const CostCoefficients& prior, const CalibrationParams& params) : params_(params) {
  reset(prior);
}

void CostCalibrator::reset(const CostCoefficients& prior) {
  prior_ = prior;
  double p[kN];
  toArray(prior, p);
  for (size_t i = 0; i < kN; ++i) {
    scale_[i] = (p[i] > 0.0 && std::isfinite(p[i])) ? p[i] : kNominal[i];
    p[i] = (p[i] > 0.0 && std::isfinite(p[i])) ? p[i] : 0.0;
  }
  prior_ = fromArray(p);
  // information of the prior alone: multipliers m = prior / scale (1, or 0 for a zero prior)
  for (size_t i = 0; i < kN * kN; ++i) info_[i] = 0.0;
  for (size_t i = 0; i < kN; ++i) {
    info_[i * kN + i] = params_.prior_weight;
    rhs_[i] = params_.prior_weight * (p[i] / scale_[i]);
  }
  coefficients_ = prior_;
  update_count_ = 0;
}

bool CostCalibrator::update(const CostFeatures& features, double measured_ms) {
  if (!std::isfinite(measured_ms) || measured_ms < 0.0) return false;
  double x[kN];
  toArray(features, x);
  for (size_t i = 0; i < kN; ++i) {
    if (!std::isfinite(x[i]) || x[i] < 0.0) return false;
    x[i] *= scale_[i];  // contribution in ms under the scale coefficient
  }
  double p[kN];
  toArray(prior_, p);
  const double f = params_.forgetting, keep = (1.0 - f) * params_.prior_weight;
  for (size_t i = 0; i < kN; ++i) {
    for (size_t j = 0; j < kN; ++j) info_[i * kN + j] = f * info_[i * kN + j] + x[i] * x[j];
    info_[i * kN + i] += keep;  // the prior's weight stays constant under forgetting
    rhs_[i] = f * rhs_[i] + x[i] * measured_ms + keep * (p[i] / scale_[i]);
  }
  ++update_count_;
  solve();
  return true;
}

void CostCalibrator::solve() {
  bool free_index[kN];
  for (bool& b : free_index) b = true;
  double m[kN];
  for (size_t round = 0; round < kN; ++round) {
    if (!choleskySolve(info_, rhs_, free_index, m)) return;  // keep the previous coefficients
    bool changed = false;
    for (size_t i = 0; i < kN; ++i)
      if (free_index[i] && m[i] < 0.0) {
        free_index[i] = false;
        changed = true;
      }
    if (!changed) break;
  }
  for (size_t i = 0; i < kN; ++i) m[i] = std::max(m[i], 0.0) * scale_[i];
  coefficients_ = fromArray(m);
}

}  // namespace scenelod::selection
