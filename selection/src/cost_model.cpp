// Frame-cost prediction (Funkhouser & Sequin 1993, §4.1, linear-sum form) and its calibration by
// regularised recursive least squares with exponential forgetting (information form, ridge toward the
// prior, non-negativity by an active set as in Lawson & Hanson's NNLS, simplified), with the shadow
// views' scales as deviations from their prior (cost_model.h).
#include "scenelod/selection/cost_model.h"

#include <algorithm>
#include <cmath>

namespace scenelod::selection {

namespace {

constexpr size_t kN = kCostTermCount;
constexpr size_t kU = kN + 3;  // CostCalibrator::kUnknowns: 6 shared multipliers, then 3 shadow deviations
// frames with shadow features before the shadow fit moves the factors
constexpr uint64_t kShadowWarmup = 2 * kU;
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
// the shadow part in the shared terms' order (no per-frame term)
void shadowToArray(const CostFeatures& f, double* a) {
  a[0] = 0.0; a[1] = f.shadow_objects; a[2] = f.shadow_triangles; a[3] = f.shadow_vertices;
  a[4] = f.shadow_line_points; a[5] = f.shadow_pixels;
}
// the prior factor of each shared term's shadow part (1 for the per-frame term, which has none)
void factorArray(const CostCoefficients& c, double* a) {
  a[0] = 1.0; a[1] = c.shadow_object_factor; a[2] = a[3] = a[4] = c.shadow_geometry_factor;
  a[5] = c.shadow_pixel_factor;
}
double saneFactor(double f) {
  return (f > 0.0 && std::isfinite(f)) ? std::clamp(f, kMinShadowFactor, kMaxShadowFactor) : 1.0;
}

// Solves the symmetric positive definite system of size n (a: n x n, row-major) restricted to the
// free indices by Cholesky; x of fixed indices is 0. Returns false when a pivot is not positive.
bool choleskySolve(const double* a, const double* b, const bool* free_index, size_t size, double* x) {
  size_t idx[kU];
  size_t n = 0;
  for (size_t i = 0; i < size; ++i)
    if (free_index[i]) idx[n++] = i;
  double l[kU * kU] = {};
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j <= i; ++j) {
      double s = a[idx[i] * size + idx[j]];
      for (size_t k = 0; k < j; ++k) s -= l[i * kU + k] * l[j * kU + k];
      if (i == j) {
        if (!(s > 0.0)) return false;
        l[i * kU + i] = std::sqrt(s);
      } else {
        l[i * kU + j] = s / l[j * kU + j];
      }
    }
  }
  double y[kU] = {};
  for (size_t i = 0; i < n; ++i) {
    double s = b[idx[i]];
    for (size_t k = 0; k < i; ++k) s -= l[i * kU + k] * y[k];
    y[i] = s / l[i * kU + i];
  }
  double z[kU] = {};
  for (size_t ii = n; ii-- > 0;) {
    double s = y[ii];
    for (size_t k = ii + 1; k < n; ++k) s -= l[k * kU + ii] * z[k];
    z[ii] = s / l[ii * kU + ii];
  }
  for (size_t i = 0; i < size; ++i) x[i] = 0.0;
  for (size_t i = 0; i < n; ++i) x[idx[i]] = z[i];
  return true;
}

// Non-negative multipliers 0..kN-1 by the active set (the indices from kN on are free of sign):
// the regularised normal equations of size n solved into m. False when a pivot is not positive.
bool activeSetSolve(const double* info, const double* rhs, size_t size, double* m) {
  bool free_index[kU];
  for (size_t i = 0; i < size; ++i) free_index[i] = true;
  for (size_t round = 0; round < kN; ++round) {
    if (!choleskySolve(info, rhs, free_index, size, m)) return false;
    bool changed = false;
    for (size_t i = 0; i < kN; ++i)
      if (free_index[i] && m[i] < 0.0) {
        free_index[i] = false;
        changed = true;
      }
    if (!changed) break;
  }
  for (size_t i = 0; i < kN; ++i) m[i] = std::max(m[i], 0.0);
  return true;
}

}  // namespace

double predictFrameMs(const CostCoefficients& c, const CostFeatures& f) {
  const double shared = c.per_frame_ms * f.frames + c.per_object_ms * f.objects + c.per_triangle_ms * f.triangles +
                        c.per_vertex_ms * f.vertices + c.per_line_point_ms * f.line_points + c.per_pixel_ms * f.pixels;
  if (f.shadow_objects == 0.0 && f.shadow_triangles == 0.0 && f.shadow_vertices == 0.0 &&
      f.shadow_line_points == 0.0 && f.shadow_pixels == 0.0)
    return shared;
  const double geometry = c.per_triangle_ms * f.shadow_triangles + c.per_vertex_ms * f.shadow_vertices +
                          c.per_line_point_ms * f.shadow_line_points;
  return shared + c.shadow_object_factor * c.per_object_ms * f.shadow_objects +
         c.shadow_pixel_factor * c.per_pixel_ms * f.shadow_pixels + c.shadow_geometry_factor * geometry;
}

CostCalibrator::CostCalibrator(const CostCoefficients& prior, const CalibrationParams& params) : params_(params) {
  reset(prior);
}

void CostCalibrator::reset(const CostCoefficients& prior) {
  double p[kN];
  toArray(prior, p);
  for (size_t i = 0; i < kN; ++i) {
    scale_[i] = (p[i] > 0.0 && std::isfinite(p[i])) ? p[i] : kNominal[i];
    p[i] = (p[i] > 0.0 && std::isfinite(p[i])) ? p[i] : 0.0;
  }
  prior_ = fromArray(p);
  prior_.shadow_object_factor = saneFactor(prior.shadow_object_factor);
  prior_.shadow_pixel_factor = saneFactor(prior.shadow_pixel_factor);
  prior_.shadow_geometry_factor = saneFactor(prior.shadow_geometry_factor);
  // information of the prior alone: multipliers m = prior / scale (1, or 0 for a zero prior), and
  // (the shadow fit) deviations 0
  for (size_t i = 0; i < kN * kN; ++i) info_[i] = 0.0;
  for (size_t i = 0; i < kN; ++i) {
    info_[i * kN + i] = params_.prior_weight;
    rhs_[i] = params_.prior_weight * (p[i] / scale_[i]);
  }
  for (size_t i = 0; i < kU * kU; ++i) shadow_info_[i] = 0.0;
  for (size_t i = 0; i < kU; ++i) {
    shadow_info_[i * kU + i] = i < kN ? params_.prior_weight : params_.shadow_prior_weight;
    shadow_rhs_[i] = i < kN ? rhs_[i] : 0.0;
  }
  for (double& s : shadow_geometry_sum_) s = 0.0;
  shadow_update_count_ = 0;
  coefficients_ = prior_;
  update_count_ = 0;
}

bool CostCalibrator::update(const CostFeatures& features, double measured_ms) {
  if (!std::isfinite(measured_ms) || measured_ms < 0.0) return false;
  double x[kN], sx[kN];
  toArray(features, x);
  shadowToArray(features, sx);
  bool shadows = false;
  for (size_t i = 0; i < kN; ++i) {
    if (!std::isfinite(x[i]) || x[i] < 0.0 || !std::isfinite(sx[i]) || sx[i] < 0.0) return false;
    shadows |= sx[i] > 0.0;
  }
  double p[kN];
  toArray(prior_, p);
  ++update_count_;
  if (shadows && params_.learn_shadow_factors) {
    // the shadow fit: regressors in ms under the scale coefficients, the shared terms' (the shadow
    // part at its prior factor included), then the shadow parts' alone: object, geometry
    // (triangles, vertices and line points at the prior's ratios), pixel
    double factor[kN], z[kU];
    factorArray(prior_, factor);
    double shadow[kN];
    for (size_t i = 0; i < kN; ++i) {
      shadow[i] = sx[i] * scale_[i] * factor[i];
      z[i] = x[i] * scale_[i] + shadow[i];
    }
    z[kN] = shadow[1];
    z[kN + 1] = shadow[2] + shadow[3] + shadow[4];
    z[kN + 2] = shadow[5];
    const double f = params_.shadow_forgetting;
    for (size_t i = 0; i < kU; ++i) {
      const double keep = (1.0 - f) * (i < kN ? params_.prior_weight : params_.shadow_prior_weight);
      for (size_t j = 0; j < kU; ++j) shadow_info_[i * kU + j] = f * shadow_info_[i * kU + j] + z[i] * z[j];
      shadow_info_[i * kU + i] += keep;
      shadow_rhs_[i] = f * shadow_rhs_[i] + z[i] * measured_ms + (i < kN ? keep * (p[i] / scale_[i]) : 0.0);
    }
    for (size_t k = 0; k < 3; ++k) shadow_geometry_sum_[k] = f * shadow_geometry_sum_[k] + shadow[2 + k];
    // an underdetermined fit (fewer frames than unknowns, twice over) does not move the factors
    if (++shadow_update_count_ >= kShadowWarmup) solveShadow();
  }
  // the shared fit, the shadow part at the current factors
  double factor[kN];
  factorArray(coefficients_, factor);
  for (size_t i = 0; i < kN; ++i) x[i] = x[i] * scale_[i] + sx[i] * scale_[i] * factor[i];
  const double f = params_.forgetting, keep = (1.0 - f) * params_.prior_weight;
  for (size_t i = 0; i < kN; ++i) {
    for (size_t j = 0; j < kN; ++j) info_[i * kN + j] = f * info_[i * kN + j] + x[i] * x[j];
    info_[i * kN + i] += keep;  // the prior's weight stays constant under forgetting
    rhs_[i] = f * rhs_[i] + x[i] * measured_ms + keep * (p[i] / scale_[i]);
  }
  solve();
  return true;
}

void CostCalibrator::solve() {
  double m[kN];
  if (!activeSetSolve(info_, rhs_, kN, m)) return;  // keep the previous coefficients
  for (size_t i = 0; i < kN; ++i) m[i] *= scale_[i];
  const CostCoefficients shared = fromArray(m);
  coefficients_.per_frame_ms = shared.per_frame_ms;
  coefficients_.per_object_ms = shared.per_object_ms;
  coefficients_.per_triangle_ms = shared.per_triangle_ms;
  coefficients_.per_vertex_ms = shared.per_vertex_ms;
  coefficients_.per_line_point_ms = shared.per_line_point_ms;
  coefficients_.per_pixel_ms = shared.per_pixel_ms;
}

void CostCalibrator::solveShadow() {
  // unconstrained: the shared multipliers here only measure the shadow deviations against them (a
  // shared one held at 0 by the active set would push its share of the frame into a deviation)
  double m[kU];
  bool free_index[kU];
  for (bool& b : free_index) b = true;
  if (!choleskySolve(shadow_info_, shadow_rhs_, free_index, kU, m)) return;  // keep the previous factors
  // a factor: prior * (shadow multiplier / shared multiplier), the prior where the shared one is 0
  const auto ratio = [](double prior, double num, double den) {
    const double r = den > 0.0 ? prior * (num / den) : prior;
    return std::isfinite(r) ? std::clamp(r, kMinShadowFactor, kMaxShadowFactor) : prior;
  };
  coefficients_.shadow_object_factor = ratio(prior_.shadow_object_factor, m[1] + m[kN], m[1]);
  coefficients_.shadow_pixel_factor = ratio(prior_.shadow_pixel_factor, m[5] + m[kN + 2], m[5]);
  // geometry: the recent shadow mix's cost at the shared multipliers plus the deviation, over its
  // cost at the shared multipliers
  double num = 0.0, den = 0.0;
  for (size_t k = 0; k < 3; ++k) {
    num += (m[2 + k] + m[kN + 1]) * shadow_geometry_sum_[k];
    den += m[2 + k] * shadow_geometry_sum_[k];
  }
  coefficients_.shadow_geometry_factor = ratio(prior_.shadow_geometry_factor, num, den);
}

}  // namespace scenelod::selection
