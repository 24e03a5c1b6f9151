#pragma once
// The frame-cost model of budget selection (Funkhouser & Sequin 1993, §4.1) and its online
// calibration from measured frame times.
//
// Form: a linear sum, predicted frame time =
//     per_frame + sum over drawn objects of (per_object + per_triangle * triangles
//       + per_vertex * vertices + per_line_point * (edges + points) + per_pixel * pixels).
// Funkhouser & Sequin predict max(geometry, pixel fill) per object. We use the linear sum because the
// engine only reports whole-frame times: a sum of linear terms is linear in the coefficients, so the
// frame total is one linear regression over six summed features and recursive least squares fits it
// exactly; the max form is piecewise and its coefficients are not identifiable from frame totals.
#include <cstddef>
#include <cstdint>

namespace scenelod::selection {

inline constexpr size_t kCostTermCount = 6;

// Milliseconds per unit of each term. Defaults are a plausible desktop GPU, to be replaced by
// calibration.
struct CostCoefficients {
  double per_frame_ms = 0.5;
  double per_object_ms = 2.0e-3;
  double per_triangle_ms = 1.0e-6;
  double per_vertex_ms = 5.0e-7;
  double per_line_point_ms = 1.0e-6;
  double per_pixel_ms = 1.0e-7;
};

// The six summed features of one frame (what was drawn), in the coefficient order above.
struct CostFeatures {
  double frames = 1.0;      // always 1: multiplies per_frame_ms
  double objects = 0.0;     // drawn objects
  double triangles = 0.0;
  double vertices = 0.0;
  double line_points = 0.0; // edges + points
  double pixels = 0.0;      // projected bounding-sphere area of drawn objects, clamped to the viewport
};

// Predicted frame time of `features` under `coefficients`. Cost: a few flops.
double predictFrameMs(const CostCoefficients& coefficients, const CostFeatures& features);

struct CalibrationParams {
  double forgetting = 0.95;    // weight of the past per frame, in (0, 1]; memory about 1/(1-f) frames
  double prior_weight = 1e-3; // ridge weight pulling each coefficient toward the prior, in units of
                               // (ms of that term)^2; it keeps collinear terms (triangles and
                               // vertices) and unexcited terms at their prior ratio
};

// Online regularised recursive least squares with forgetting, in information form over a 6x6
// system. Coefficients are parameterised as multipliers of the prior (theta_i = m_i * prior_i), so
// every feature is measured in milliseconds and the ridge term is scale-free; each update solves
// the regularised normal equations with non-negativity enforced by an active set (negative
// multipliers are fixed at 0 and the rest re-solved). Plain data, no allocation; not thread-safe
// (one calibrator per selector, updated on the selecting thread).
class CostCalibrator {
 public:
  explicit CostCalibrator(const CostCoefficients& prior = CostCoefficients(),
                          const CalibrationParams& params = CalibrationParams());

  // Forgets everything and restarts from `prior`.
  void reset(const CostCoefficients& prior);
  // Adds one frame: what was drawn and what it measured. Non-finite or negative times are ignored
  // (returns false). Cost: one 6x6 Cholesky solve (at most 6 with the active set).
  bool update(const CostFeatures& features, double measured_ms);

  const CostCoefficients& coefficients() const { return coefficients_; }
  const CostCoefficients& prior() const { return prior_; }
  uint64_t updateCount() const { return update_count_; }

 private:
  void solve();

  CostCoefficients prior_;
  CostCoefficients coefficients_;
  CalibrationParams params_;
  double scale_[kCostTermCount] = {};   // prior coefficient (or a nominal one when the prior is 0)
  double info_[kCostTermCount * kCostTermCount] = {};
  double rhs_[kCostTermCount] = {};
  uint64_t update_count_ = 0;
};

}  // namespace scenelod::selection
