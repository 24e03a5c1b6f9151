#pragma once
// The frame-cost model of budget selection (Funkhouser & Sequin 1993, §4.1) and its online
// calibration from measured frame times.
//
// Form: a linear sum, predicted frame time =
//     per_frame + sum over drawn objects of (per_object + per_triangle * triangles
//       + per_vertex * vertices + per_line_point * (edges + points) + per_pixel * pixels),
// where an object drawn in a shadow view (frames with views) counts its object, pixel and geometry
// terms at the shadow kind's scales: SelectionParams::view_kinds[kShadow] times the factors below,
// which the calibration learns (docs/SELECTION.md, "Cost model").
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
  // Shadow views (frames with views): the learnt factors on the shadow kind's object, pixel and
  // geometry scales (SelectionParams::view_kinds[kShadow]; 1 = those scales as given). Each is
  // within [kMinShadowFactor, kMaxShadowFactor]. As a prior (SelectorConfig::initial_cost,
  // setSelectorCostModel) they are where the calibration starts and what it holds them at until
  // the frames tell the shadow passes apart from the others.
  double shadow_object_factor = 1.0;
  double shadow_pixel_factor = 1.0;
  double shadow_geometry_factor = 1.0;
};

inline constexpr double kMinShadowFactor = 1.0 / 32.0;
inline constexpr double kMaxShadowFactor = 8.0;

// The six summed features of one frame (what was drawn), in the coefficient order above.
struct CostFeatures {
  double frames = 1.0;      // always 1: multiplies per_frame_ms
  double objects = 0.0;     // drawn objects
  double triangles = 0.0;
  double vertices = 0.0;
  double line_points = 0.0; // edges + points
  double pixels = 0.0;      // projected bounding-sphere area of drawn objects, clamped to the viewport
  // Frames with views: the part drawn in shadow views, each at the shadow kind's scale of
  // SelectionParams::view_kinds (before the learnt factors); the fields above hold the other views'
  // part, each at its kind's scale. 0 in frames without views.
  double shadow_objects = 0.0;
  double shadow_triangles = 0.0;
  double shadow_vertices = 0.0;
  double shadow_line_points = 0.0;
  double shadow_pixels = 0.0;
};

// Predicted frame time of `features` under `coefficients` (the shadow part at the shadow factors).
// Cost: a few flops.
double predictFrameMs(const CostCoefficients& coefficients, const CostFeatures& features);

struct CalibrationParams {
  double forgetting = 0.95;    // weight of the past per frame, in (0, 1]; memory about 1/(1-f) frames
  double prior_weight = 1e-3; // ridge weight pulling each coefficient toward the prior, in units of
                               // (ms of that term)^2; it keeps collinear terms (triangles and
                               // vertices) and unexcited terms at their prior ratio
  // the shadow factors' own fit (docs/SELECTION.md, "Cost model"): a slower memory, since a
  // shadow pass's cost relative to the other views' is a property of the renderer, not of the load
  // (about 1/(1-f) = 500 frames; in (0, 1])
  double shadow_forgetting = 0.998;
  // ridge weight (ms^2) holding each shadow factor at its prior: it decides where the factors stay
  // while the shadow features move in step with the others (a fixed multiple of them, which one
  // frame time cannot tell apart) and how much a term must vary to be learnt
  double shadow_prior_weight = 1.0;
  bool learn_shadow_factors = true;  // false: the shadow factors stay at the prior
};

// Online regularised recursive least squares with forgetting, in information form over a 6x6
// system. Coefficients are parameterised as multipliers of the prior (theta_i = m_i * prior_i), so
// every feature is measured in milliseconds and the ridge term is scale-free; each update solves
// the regularised normal equations with non-negativity enforced by an active set (negative
// multipliers are fixed at 0 and the rest re-solved). The shadow part of a frame's features enters
// this fit at the current shadow factors.
// The shadow factors have a fit of their own, updated only by frames with shadow features: a
// shadow term i costs (m_i + d_k) * prior_i * prior factor per unit, so the frame is linear in 6
// shared multipliers m and 3 shadow deviations d (object; geometry, shared by triangles, vertices
// and line points; pixel): a 9x9 system with the slower forgetting shadow_forgetting, whose ridge
// pulls m toward the prior and d toward 0 (weight shadow_prior_weight). The factors read out as
// prior factor * (m_i + d_k) / m_i, the geometry one over the recent mix of shadow triangles,
// vertices and line points, clamped to [kMinShadowFactor, kMaxShadowFactor] (the prior where m_i
// is 0); they stay at the prior for the first 18 frames with shadow features (twice the unknowns:
// an underdetermined fit does not move them). Without shadow features the
// factors stay at the prior exactly and the 6x6 fit is what it was before shadows existed. Plain
// data, no allocation; not thread-safe (one calibrator per selector, updated on the selecting
// thread).
class CostCalibrator {
 public:
  explicit CostCalibrator(const CostCoefficients& prior = CostCoefficients(),
                          const CalibrationParams& params = CalibrationParams());

  // Forgets everything and restarts from `prior`.
  void reset(const CostCoefficients& prior);
  // Adds one frame: what was drawn and what it measured. Non-finite or negative times are ignored
  // (returns false). Cost: one 6x6 Cholesky solve (at most 6 with the active set), and with shadow
  // features one 9x9 solve as well.
  bool update(const CostFeatures& features, double measured_ms);

  const CostCoefficients& coefficients() const { return coefficients_; }
  const CostCoefficients& prior() const { return prior_; }
  uint64_t updateCount() const { return update_count_; }

 private:
  void solve();
  void solveShadow();

  static constexpr size_t kShadowTerms = 3;  // object, geometry, pixel
  static constexpr size_t kUnknowns = kCostTermCount + kShadowTerms;

  CostCoefficients prior_;
  CostCoefficients coefficients_;
  CalibrationParams params_;
  double scale_[kCostTermCount] = {};   // prior coefficient (or a nominal one when the prior is 0)
  double info_[kCostTermCount * kCostTermCount] = {};
  double rhs_[kCostTermCount] = {};
  // the shadow factors' fit: 6 shared multipliers, then 3 shadow deviations
  double shadow_info_[kUnknowns * kUnknowns] = {};
  double shadow_rhs_[kUnknowns] = {};
  double shadow_geometry_sum_[3] = {};  // forgotten sums of the shadow geometry regressors (their mix)
  uint64_t update_count_ = 0;
  uint64_t shadow_update_count_ = 0;    // frames the shadow fit has seen
};

}  // namespace scenelod::selection
