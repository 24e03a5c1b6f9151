// Level transitions: the morph factor along a camera path, fades timed by dt_ms, the budget counting
// both levels of a fade, and the bad inputs.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "scenelod/lodcore/chain.h"
#include "selection/selection_fixtures.h"

using namespace scenelod;
using namespace scenelod::selection;
using namespace scenelod::selection::test;

namespace {

// One object at the origin on a chain of `levels` levels (w_k = 0.01 * 2^(k-1)), every level with
// morph data when `morph` is set.
SyntheticScene oneObject(size_t levels, bool morph) {
  SyntheticScene s;
  std::vector<float> w(levels);
  std::vector<uint32_t> t(levels), v(levels), lp(levels, 0);
  for (size_t k = 0; k < levels; ++k) {
    w[k] = k == 0 ? 0.0f : 0.01f * static_cast<float>(1u << (k - 1));
    t[k] = 40000u >> k;
    v[k] = t[k] / 2 + 2;
  }
  s.table.addChain(Span<const float>(w.data(), w.size()), Span<const uint32_t>(t.data(), t.size()),
                   Span<const uint32_t>(v.data(), v.size()), Span<const uint32_t>(lp.data(), lp.size()));
  for (auto& m : s.table.has_morph) m = morph ? 1 : 0;
  s.centers.push_back(glm::vec3(0.0f));
  s.radii.push_back(1.0f);
  s.scales.push_back(1.0f);
  s.importance.push_back(1.0f);
  s.chains.push_back(0);
  s.must_draw.push_back(0);
  return s;
}

// The transition outputs of a job.
struct Outputs {
  std::vector<int8_t> levels, previous;
  std::vector<float> morph, fade;
  void attach(SelectionJob& job, size_t n) {
    previous.assign(n, 0);
    morph.assign(n, -1.0f);
    fade.assign(n, -1.0f);
    job.previous_levels_out = Span<int8_t>(previous.data(), n);
    job.morph_out = Span<float>(morph.data(), n);
    job.fade_out = Span<float>(fade.data(), n);
  }
};

Camera cameraAtDistance(float d) { return makeCamera(glm::vec3(0.0f, 0.0f, d)); }

}  // namespace

// Moving away from one object and back, in small steps: level + morph factor (where the object
// is drawn between its levels) changes little per frame, also across every switch; the factor is
// exactly 1 on the last frame before each switch to a coarser level and on the first frame after a
// switch to a finer one... to within the step there, and 0 on the coarser level's side.
TEST(Transitions, MorphFactorIsContinuousAlongAPathAndOneAtTheSwitch) {
  const SyntheticScene s = oneObject(6, true);
  Owned o(makeContext(1));
  std::vector<float> dist;
  for (float d = 3.0f; d < 3000.0f; d *= 1.002f) dist.push_back(d);
  for (size_t k = dist.size(); k-- > 0;) dist.push_back(dist[k]);
  int prev_level = -2;
  float prev_morph = 0.0f;
  int coarser = 0, finer = 0;
  float max_morph[6] = {};
  for (size_t f = 0; f < dist.size(); ++f) {
    const Camera cam = cameraAtDistance(dist[f]);
    Outputs out;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, out.levels, &st);
    job.params.mode = SelectionMode::kDistance;
    job.params.transitions = Transitions::kMorph;
    job.params.dt_ms = 16.0f;
    out.attach(job, 1);
    ASSERT_TRUE(job.run()) << job.error();
    const int l = out.levels[0];
    const float m = out.morph[0];
    ASSERT_GE(l, 0);
    ASSERT_GE(m, 0.0f);
    ASSERT_LE(m, 1.0f);
    // adjacent switches with morph data are morphs: no fade ever runs
    EXPECT_EQ(out.previous[0], l) << "frame " << f;
    EXPECT_EQ(out.fade[0], 1.0f) << "frame " << f;
    if (l == 5) {
      EXPECT_EQ(m, 0.0f);
    }  // the coarsest level has nothing to morph to
    max_morph[l] = std::max(max_morph[l], m);
    if (prev_level >= 0) {
      const float g = static_cast<float>(l) + m, g0 = static_cast<float>(prev_level) + prev_morph;
      EXPECT_LT(std::fabs(g - g0), 0.05f) << "frame " << f << " level " << prev_level << " -> " << l;
      if (l == prev_level + 1) {
        ++coarser;
        EXPECT_EQ(prev_morph, 1.0f) << "frame " << f;  // exactly 1 where the switch happens
        EXPECT_EQ(m, 0.0f) << "frame " << f;
      } else if (l == prev_level - 1) {
        ++finer;
        EXPECT_EQ(prev_morph, 0.0f) << "frame " << f;
        EXPECT_GT(m, 0.99f) << "frame " << f;
      } else {
        EXPECT_EQ(l, prev_level) << "frame " << f;
      }
    }
    prev_level = l;
    prev_morph = m;
  }
  EXPECT_EQ(coarser, 5);
  EXPECT_EQ(finer, 5);
  for (int k = 0; k < 5; ++k) EXPECT_EQ(max_morph[k], 1.0f) << "level " << k;
}

// Many objects in one frame (full blocks of slots), from near to far: each object's factor is 0
// below its level's band, the smoothstep of its log position inside it (the selector's log is a
// series, within 1e-3) and 1 from the band's end; the objects skipped as "factor 0" are exactly
// those below the band.
TEST(Transitions, MorphFactorsOfManyObjectsFollowTheirBands) {
  SyntheticScene s = oneObject(6, true);
  s.centers.clear();
  s.radii.clear();
  s.scales.clear();
  s.importance.clear();
  s.chains.clear();
  s.must_draw.clear();
  std::vector<float> dist;
  for (float d = 3.0f; d < 3000.0f; d *= 1.001f) dist.push_back(d);
  for (float d : dist) {
    s.centers.push_back(glm::vec3(0.0f, 0.0f, -d));
    s.radii.push_back(1.0f);
    s.scales.push_back(1.0f);
    s.importance.push_back(1.0f);
    s.chains.push_back(0);
    s.must_draw.push_back(0);
  }
  const size_t n = dist.size();
  Owned o(makeContext(n));
  const Camera cam = makeCamera();
  Outputs out;
  SelectionStats st;
  SelectionJob job = makeJob(s, o.ctx, &cam, out.levels, &st);
  job.params.mode = SelectionMode::kDistance;
  job.params.transitions = Transitions::kMorph;
  out.attach(job, n);
  ASSERT_TRUE(job.run()) << job.error();
  const float h1 = 1.0f + job.params.hysteresis;
  const double band = job.params.morph_band;
  size_t below = 0, inside = 0, at_one = 0;
  for (size_t i = 0; i < n; ++i) {
    const int l = out.levels[i];
    const float m = out.morph[i];
    ASSERT_GE(l, 0) << "object " << i;
    if (l == 5) {
      EXPECT_EQ(m, 0.0f) << "object " << i;
      continue;
    }
    // q = X R / scale with R the pixel size at the sphere's nearest point
    const double q = static_cast<double>(pixelSize(cam, dist[i] - 1.0f));
    const double hi = s.table.cell_width[l + 1] / h1;
    const double lo = l == 0 ? 0.5 * hi : s.table.cell_width[l];
    const double start = hi * std::pow(lo / hi, band);
    if (q < start * (1.0 - 1e-5)) {
      EXPECT_EQ(m, 0.0f) << "object " << i << " level " << l;
      ++below;
    } else if (q > start * (1.0 + 1e-5) && q < hi * (1.0 - 1e-5)) {
      const double t = std::log(q / start) / std::log(hi / start);
      EXPECT_GT(m, 0.0f) << "object " << i << " level " << l;
      EXPECT_NEAR(m, t * t * (3.0 - 2.0 * t), 5e-3) << "object " << i << " level " << l;
      ++inside;
    } else if (q > hi * (1.0 + 1e-5)) {
      EXPECT_EQ(m, 1.0f) << "object " << i << " level " << l;
      ++at_one;
    }
  }
  EXPECT_GT(below, 500u);
  EXPECT_GT(inside, 500u);
  EXPECT_GT(at_one, 50u);
}

// Without morph data (or in fade mode) the same path fades at every switch: a fade lasts fade_ms
// at the caller's dt_ms, the new level's weight rising as elapsed / fade_ms.
TEST(Transitions, AFadeLastsItsDurationAtTheGivenFrameTime) {
  for (const bool morph_data : {false, true}) {
    for (const float dt : {10.0f, 25.0f, 7.0f}) {
      const SyntheticScene s = oneObject(6, morph_data);
      Owned o(makeContext(1));
      int fade_frames = 0, fades_started = 0;
      int8_t before = -2, target = -2;
      for (int f = 0; f < 200; ++f) {
        // a jump of three levels at frame 5, then a still camera
        const Camera cam = cameraAtDistance(f < 5 ? 10.0f : 80.0f);
        Outputs out;
        SelectionStats st;
        SelectionJob job = makeJob(s, o.ctx, &cam, out.levels, &st);
        job.params.mode = SelectionMode::kDistance;
        job.params.transitions = morph_data ? Transitions::kMorph : Transitions::kFade;
        job.params.dt_ms = dt;
        job.params.fade_ms = 250.0f;
        out.attach(job, 1);
        ASSERT_TRUE(job.run()) << job.error();
        if (f == 4) before = out.levels[0];
        if (f == 5) {
          target = out.levels[0];
          ASSERT_GE(target - before, 2);
          ++fades_started;
        }
        if (out.previous[0] != out.levels[0]) {
          EXPECT_EQ(out.previous[0], before);
          EXPECT_EQ(out.levels[0], target);
          EXPECT_FLOAT_EQ(out.fade[0], static_cast<float>(fade_frames) * dt / 250.0f);
          EXPECT_EQ(st.fading_count, 1u);
          EXPECT_GT(st.fade_cost_ms, 0.0);
          ++fade_frames;
        } else {
          EXPECT_EQ(out.fade[0], 1.0f);
          EXPECT_EQ(st.fading_count, 0u);
        }
      }
      EXPECT_EQ(fades_started, 1);
      // frames 5 .. 5 + k - 1 fade, k = ceil(250 / dt): the fade covers its 250 ms
      EXPECT_EQ(fade_frames, static_cast<int>(std::ceil(250.0f / dt))) << "dt " << dt;
    }
  }
}

// Adjacent switches fade too when the level has no morph data (morph mode), and in fade mode;
// a fade reversed half-way continues from the same mix instead of restarting.
TEST(Transitions, AdjacentSwitchesFadeWithoutMorphDataAndReversalsKeepTheMix) {
  const SyntheticScene s = oneObject(6, false);
  Owned o(makeContext(1));
  auto frame = [&](float d, Outputs& out) {
    const Camera cam = cameraAtDistance(d);
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, out.levels, &st);
    job.params.mode = SelectionMode::kDistance;
    job.params.transitions = Transitions::kMorph;
    job.params.dt_ms = 50.0f;
    job.params.fade_ms = 200.0f;
    out.attach(job, 1);
    EXPECT_TRUE(job.run());
  };
  Outputs a, b, c, d;
  frame(20.0f, a);
  frame(40.0f, b);  // one level coarser
  ASSERT_EQ(b.levels[0], a.levels[0] + 1);
  EXPECT_EQ(b.previous[0], a.levels[0]);
  EXPECT_EQ(b.fade[0], 0.0f);
  EXPECT_EQ(b.morph[0], 0.0f);  // no morph data
  frame(40.0f, c);
  EXPECT_EQ(c.fade[0], 0.25f);
  frame(20.0f, d);  // back: the old level's weight was 0.5 after this frame's 50 ms, and stays
  ASSERT_EQ(d.levels[0], a.levels[0]);
  EXPECT_EQ(d.previous[0], b.levels[0]);
  EXPECT_EQ(d.fade[0], 0.5f);
}

// Objects entering the view switch at once (they were off-screen); an object dropped by the budget
// fades out when the fades' share of the budget holds its level, and fades in when drawn again.
TEST(Transitions, EnteringTheViewIsImmediateDroppingFades) {
  // two objects side by side on a chain whose levels cost the same
  SyntheticScene s = oneObject(4, false);
  for (auto& t : s.table.triangle_count) t = 1000;
  for (auto& v : s.table.vertex_count) v = 600;
  s.centers.push_back(glm::vec3(0.5f, 0.0f, 0.0f));
  s.radii.push_back(1.0f);
  s.scales.push_back(1.0f);
  s.importance.push_back(2.0f);  // the one kept
  s.chains.push_back(0);
  s.must_draw.push_back(0);
  for (const float share : {1.0f, 0.0f}) {
    Owned o(makeContext(2));
    auto frame = [&](const Camera& cam, float budget, Outputs& out, SelectionStats& st) {
      SelectionJob job = makeJob(s, o.ctx, &cam, out.levels, &st);
      job.params.mode = budget > 0.0f ? SelectionMode::kBudget : SelectionMode::kDistance;
      job.params.budget_ms = budget > 0.0f ? budget : 1.0f;
      job.params.calibrate = false;
      job.params.transitions = Transitions::kFade;
      job.params.fade_budget_share = share;
      job.params.min_drop_px = 0.0f;  // the budget may drop any object
      out.attach(job, 2);
      EXPECT_TRUE(job.run()) << job.error();
    };
    Camera away = cameraAtDistance(10.0f);
    away.target = glm::vec3(0.0f, 0.0f, 20.0f);  // looking away
    Outputs a, b, c, d;
    SelectionStats st;
    frame(away, 0.0f, a, st);
    EXPECT_EQ(a.levels[0], -1);
    EXPECT_EQ(a.previous[0], -1);
    frame(cameraAtDistance(10.0f), 100.0f, b, st);
    ASSERT_GE(b.levels[0], 0);
    ASSERT_GE(b.levels[1], 0);
    EXPECT_EQ(b.previous, b.levels);  // entered the view: no fade
    EXPECT_EQ(b.fade[0], 1.0f);
    // room for one object and a half: the less important one is dropped
    double cost = 0.0, benefit = 0.0;
    ASSERT_TRUE(selectorLastPoint(o.ctx, 0, b.levels[0], &cost, &benefit));
    const double per_frame = selectorCostModel(o.ctx).per_frame_ms;
    frame(cameraAtDistance(10.0f), static_cast<float>(per_frame + 1.5 * cost), c, st);
    ASSERT_EQ(c.levels[0], -1);
    ASSERT_GE(c.levels[1], 0);
    if (share == 1.0f) {
      EXPECT_EQ(c.previous[0], b.levels[0]);  // fading out
      EXPECT_EQ(c.fade[0], 0.0f);
      EXPECT_EQ(st.fading_count, 1u);
      EXPECT_NEAR(st.predicted_ms, per_frame + 2.0 * cost, 1e-5 * st.predicted_ms);
    } else {
      EXPECT_EQ(c.previous[0], -1);  // no share of the budget for fades: a hard switch
      EXPECT_EQ(st.fading_count, 0u);
    }
    // a large budget again: drawn, fading in (after a fade-out of one frame, from the same mix)
    frame(cameraAtDistance(10.0f), 100.0f, d, st);
    EXPECT_GE(d.levels[0], 0);
    EXPECT_EQ(d.previous[0], -1);
    EXPECT_FLOAT_EQ(d.fade[0], share == 1.0f ? 1.0f - 1000.0f / 60.0f / 250.0f : 0.0f);
  }
}

// Budget mode counts both levels of a fade: predicted_ms holds each fading object's outgoing level,
// and the fades that were running before the frame are reserved before the choice, so that the
// chosen levels plus those fades fit the budget.
TEST(Transitions, BudgetCountsBothLevelsWhileAFadeRuns) {
  SyntheticScene s = makeScene(7, 300, 6, 6, 60.0f);
  Owned o(makeContext(300));
  const size_t n = s.centers.size();
  const Camera cam = makeCamera();
  const double per_frame = selectorCostModel(o.ctx).per_frame_ms;
  double full = 0.0;
  int frames_with_continuing_fades = 0;
  std::vector<int8_t> last_levels(n, -1), last_previous(n, -1);
  for (int f = 0; f < 12; ++f) {
    Outputs out;
    SelectionStats st;
    SelectionJob job = makeJob(s, o.ctx, &cam, out.levels, &st);
    job.params.mode = SelectionMode::kBudget;
    job.params.calibrate = false;
    job.params.transitions = Transitions::kFade;
    job.params.dt_ms = 20.0f;
    job.params.fade_ms = 100.0f;
    job.params.fade_budget_share = 0.25f;
    // generous first, then a budget a third of what the first frame drew, shrinking further
    job.params.budget_ms = f == 0 ? 1000.0f : static_cast<float>(per_frame + (full - per_frame) / (1.2 + 0.1 * f));
    out.attach(job, n);
    ASSERT_TRUE(job.run()) << job.error();
    if (f == 0) full = st.predicted_ms;
    double levels_cost = 0.0, fade_cost = 0.0, continuing = 0.0;
    uint32_t fading = 0;
    for (size_t i = 0; i < n; ++i) {
      double c = 0.0, b = 0.0;
      if (out.levels[i] >= 0) {
        ASSERT_TRUE(selectorLastPoint(o.ctx, i, out.levels[i], &c, &b));
        levels_cost += c;
      }
      if (out.previous[i] != out.levels[i] && out.previous[i] >= 0) {
        ASSERT_TRUE(selectorLastPoint(o.ctx, i, out.previous[i], &c, &b));
        fade_cost += c;
        ++fading;
        // a fade started before this frame and not reversed in it (a reversal's outgoing level is
        // last frame's level, chosen in this frame like any switch)
        if (out.fade[i] > 0.0f && out.previous[i] == last_previous[i] && last_previous[i] != last_levels[i])
          continuing += c;
      }
    }
    last_levels = out.levels;
    last_previous = out.previous;
    EXPECT_EQ(st.fading_count, fading) << "frame " << f;
    EXPECT_NEAR(st.fade_cost_ms, fade_cost, 1e-6 * (1.0 + fade_cost)) << "frame " << f;
    EXPECT_NEAR(st.predicted_ms, per_frame + levels_cost + fade_cost, 1e-6 * st.predicted_ms) << "frame " << f;
    EXPECT_GE(st.mandatory_ms, per_frame + continuing - 1e-6) << "frame " << f;
    // all fades within their share of the objects' budget
    if (f > 0) {
      EXPECT_LE(fade_cost, 0.25 * (job.params.budget_ms - per_frame) * (1.0 + 1e-6)) << "frame " << f;
    }
    if (f > 0 && !(st.flags & kFlagOverBudget)) {
      EXPECT_LE(per_frame + levels_cost + continuing, job.params.budget_ms * (1.0 + 1e-6)) << "frame " << f;
    }
    if (f > 1 && continuing > 0.0) ++frames_with_continuing_fades;
  }
  EXPECT_GT(frames_with_continuing_fades, 3);
}

// The levels do not depend on transitions in distance mode; with fade_ms = 0 no fade runs.
TEST(Transitions, DistanceLevelsAreTheSameWithAndWithoutTransitions) {
  SyntheticScene s = makeScene(3, 500, 5, 6, 80.0f, true);
  Owned a(makeContext(500)), b(makeContext(500));
  for (int f = 0; f < 20; ++f) {
    const Camera cam = makeCamera(glm::vec3(0.5f * f, 0.0f, -2.0f * f));
    Outputs none, fade;
    SelectionStats sa, sb;
    SelectionJob ja = makeJob(s, a.ctx, &cam, none.levels, &sa);
    SelectionJob jb = makeJob(s, b.ctx, &cam, fade.levels, &sb);
    ja.params.mode = jb.params.mode = SelectionMode::kDistance;
    jb.params.transitions = Transitions::kFade;
    jb.params.fade_ms = 0.0f;
    none.attach(ja, 500);
    fade.attach(jb, 500);
    ASSERT_TRUE(ja.run());
    ASSERT_TRUE(jb.run());
    EXPECT_EQ(none.levels, fade.levels);
    EXPECT_EQ(none.previous, none.levels);  // no transitions: "no fade"
    EXPECT_EQ(fade.previous, fade.levels);
    EXPECT_EQ(sa.predicted_ms, sb.predicted_ms);
    for (size_t i = 0; i < 500; ++i) EXPECT_EQ(none.fade[i], 1.0f);
  }
}

TEST(Transitions, BadInputIsRefusedWithAClearError) {
  SyntheticScene s = oneObject(4, false);
  Owned o(makeContext(1));
  const Camera cam = makeCamera(glm::vec3(0.0f, 0.0f, 10.0f));
  Outputs out;
  SelectionStats st;
  const SelectionJob good = makeJob(s, o.ctx, &cam, out.levels, &st);
  ASSERT_TRUE(good.validate());
  auto expectError = [](SelectionJob job, const std::string& word) {
    const char* e = job.error();
    ASSERT_NE(e, nullptr) << word;
    EXPECT_NE(std::string(e).find(word), std::string::npos) << e;
    EXPECT_FALSE(job.run());
  };
  const float nan = std::nanf("");
  for (const float bad : {-1.0f, nan, INFINITY}) {
    SelectionJob j = good;
    j.params.dt_ms = bad;
    expectError(j, "dt_ms");
    j = good;
    j.params.fade_ms = bad;
    expectError(j, "fade_ms");
  }
  for (const float bad : {0.0f, -0.5f, 1.5f, nan}) {
    SelectionJob j = good;
    j.params.morph_band = bad;
    expectError(j, "morph_band");
  }
  for (const float bad : {-0.1f, 1.5f, nan}) {
    SelectionJob j = good;
    j.params.fade_budget_share = bad;
    expectError(j, "fade_budget_share");
  }
  SelectionJob j = good;
  j.params.morph_band = 1.0f;
  j.params.dt_ms = 0.0f;
  j.params.fade_ms = 0.0f;
  EXPECT_TRUE(j.validate());  // the edges are valid
  std::vector<float> two(2);
  j = good;
  j.fade_out = Span<float>(two.data(), 2);
  expectError(j, "fade_out");
  std::vector<uint8_t> morph(3, 1);
  j = good;
  j.levels.has_morph = Span<const uint8_t>(morph.data(), morph.size());
  expectError(j, "has_morph");
  View v;
  v.camera = cam;
  j = good;
  j.views = Span<const View>(&v, 1);
  j.params.transitions = Transitions::kFade;
  expectError(j, "transitions");
}

// a real chain: every level but the last carries geomorph targets, and the level table built from
// the chain says so (the rows added from counts alone say nothing)
TEST(Transitions, LevelTableKnowsWhichChainLevelsHaveMorphTargets) {
  Mesh sphere;
  for (int i = 0; i <= 24; ++i)
    for (int j = 0; j <= 48; ++j) {
      const float th = 3.14159265f * float(i) / 24.0f, ph = 6.2831853f * float(j) / 48.0f;
      sphere.positions.push_back({std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)});
    }
  for (uint32_t i = 0; i < 24; ++i)
    for (uint32_t j = 0; j < 48; ++j) {
      const uint32_t a = i * 49 + j, b = a + 1, c = a + 49, d = c + 1;
      sphere.triangles.insert(sphere.triangles.end(), {a, c, b, b, c, d});
    }
  ChainParams cp;
  cp.level_count = 4;
  LodChain chain;
  ASSERT_TRUE(buildChain(sphere, cp, chain).ok());
  ASSERT_GE(chain.levelCount(), 3u);
  LevelTableData table;
  table.addChain(chain);
  ASSERT_EQ(table.has_morph.size(), chain.levelCount());
  for (size_t l = 0; l < chain.levelCount(); ++l) {
    EXPECT_EQ(table.has_morph[l] != 0, !chain.levels[l].morph.empty()) << "level " << l;
    EXPECT_EQ(table.has_morph[l] != 0, l + 1 < chain.levelCount()) << "level " << l;
  }
}

// a level whose next level draws thick edges or points does not morph into it (a morph cannot grow
// a triangle into an edge, the switch would pop): the table says fade there, and only there
TEST(Transitions, SwitchIntoALevelWithEdgesFadesInsteadOfMorphing) {
  LodChain chain;
  for (int k = 0; k < 4; ++k) {
    LodLevel l;
    l.cell_width = 0.1f * float(1 << k);
    l.mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    if (k == 2) {
      l.mesh.edges = {0, 1};  // level 2 draws a thick edge where level 1 drew a triangle
    } else {
      l.mesh.triangles = {0, 1, 2};
    }
    if (k + 1 < 4) l.morph.positions.assign(3, glm::vec3(0.0f));
    chain.levels.push_back(l);
  }
  LevelTableData table;
  table.addChain(chain);
  ASSERT_EQ(table.has_morph.size(), 4u);
  EXPECT_EQ(table.has_morph[0], 1);  // 0 -> 1: triangles into triangles
  EXPECT_EQ(table.has_morph[1], 0);  // 1 -> 2: the next level draws an edge
  EXPECT_EQ(table.has_morph[2], 1);  // 2 -> 3: triangles again
  EXPECT_EQ(table.has_morph[3], 0);  // the last level has no next level
}
