#include "replay_report.h"

#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>

#include "scenelod/eval/plot.h"
#include "scenelod/lodcore/atomic_file.h"

namespace scenelod::tool {

using namespace scenelod::selection;

namespace {

std::string num(double v, int digits = 3) {
  char b[64];
  std::snprintf(b, sizeof(b), "%.*f", digits, v);
  return b;
}

}  // namespace

void ReplayRunDigest::add(const ReplayLogFrame& f) {
  summary.add(f);
  if (seen_ == 0) {
    has_budget = f.has_budget;
    budget_ms = f.budget_ms;
  } else {
    switches_per_second[static_cast<long>(f.time_s)] += f.switches;
  }
  if (seen_++ % stride != 0) return;
  points.push_back({f.frame, f.time_s, f.predicted_ms, f.measured_ms, f.budget_ms, f.has_measured, f.has_budget, f.switches});
  if (points.size() <= kMaxPoints) return;
  // keep every other point: the kept frames are then multiples of twice the stride
  for (size_t i = 0; 2 * i < points.size(); ++i) points[i] = points[2 * i];
  points.resize((points.size() + 1) / 2);
  stride *= 2;
}

ReplayRunDigest digestOf(const std::vector<ReplayLogFrame>& log) {
  ReplayRunDigest d;
  for (const ReplayLogFrame& f : log) d.add(f);
  return d;
}

Error writeReplayReport(const std::string& md_path, const ReplayReportInput& in, std::vector<std::string>& summary) {
  summary.clear();
  std::ostringstream o;
  o << "# Replay report\n\n";
  o << "- replay: `" << in.replay_path << "`\n- scene: `" << in.scene_path << "`\n";
  if (in.header) {
    const ReplayHeader& h = *in.header;
    o << "- viewport " << h.viewport_width_px << " x " << h.viewport_height_px << ", fov " << num(h.fov_y_deg, 1)
      << " deg, " << num(h.pixels_per_cell, 2) << " pixels per cell, " << in.frame_count << " frames\n";
  }
  if (!in.command.empty()) o << "- command: `" << in.command << "`\n";
  o << "\n## Summary\n\n| run | mode | frames | objects | mean predicted ms | mean measured ms | |pred - meas| / meas | "
       "frames within +10 % of budget (after 30) | over-budget flags | switches / object / s | mean triangles |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (size_t r = 0; r < in.runs.size(); ++r) {
    const ReplayRunDigest& run = *in.runs[r];
    const ReplaySummary s = run.summary.summary();
    const bool budget = run.has_budget;
    std::string within = "-";
    if (s.budget_frames) within = num(100.0 * s.within_10_percent / s.budget_frames, 1) + " % (" + std::to_string(s.within_10_percent) + "/" + std::to_string(s.budget_frames) + ")";
    o << "| " << in.run_names[r] << " | " << (budget ? "budget " + num(run.budget_ms, 2) + " ms" : std::string("distance")) << " | " << s.frames
      << " | " << s.objects << " | " << num(s.mean_predicted_ms) << " | " << num(s.mean_measured_ms) << " | "
      << num(100.0 * s.mean_abs_prediction_error, 1) << " % | " << within << " | " << s.over_budget_flagged << " | "
      << num(s.switches_per_object_per_second, 4) << " | " << num(s.mean_triangles, 0) << " |\n";
    char line[256];
    if (budget)
      std::snprintf(line, sizeof(line), "%s: budget %.2f ms, measured within +10%% on %s of frames after warm-up, %.4f switches/object/s",
                    in.run_names[r].c_str(), run.budget_ms, within.c_str(), s.switches_per_object_per_second);
    else
      std::snprintf(line, sizeof(line), "%s: distance mode, mean measured %.2f ms, %.0f triangles/frame, %.4f switches/object/s",
                    in.run_names[r].c_str(), s.mean_measured_ms, s.mean_triangles, s.switches_per_object_per_second);
    summary.push_back(line);
  }
  o << "\nMeasured times come from the replay file where it has them, otherwise from the synthetic renderer "
       "(true costs known, 5 % Gaussian noise, seeded); the selector learns its cost model online from them.\n";

  o << "\n## Level histogram (share of object-frames)\n\n| run | not drawn |";
  size_t max_levels = 0;
  for (const ReplayRunDigest* run : in.runs) max_levels = std::max(max_levels, run->summary.summary().level_histogram.size());
  for (size_t k = 1; k < max_levels; ++k) o << " L" << (k - 1) << " |";
  o << "\n|---|";
  for (size_t k = 0; k < max_levels; ++k) o << "---|";
  o << "\n";
  for (size_t r = 0; r < in.runs.size(); ++r) {
    const ReplaySummary s = in.runs[r]->summary.summary();
    size_t total = 0;
    for (size_t c : s.level_histogram) total += c;
    o << "| " << in.run_names[r] << " |";
    for (size_t k = 0; k < max_levels; ++k)
      o << " " << num(total ? 100.0 * (k < s.level_histogram.size() ? s.level_histogram[k] : 0) / total : 0.0, 1) << " % |";
    o << "\n";
  }

  // the runs replay the same frames, so their points are the same frames
  const size_t stride = in.runs.empty() ? 1 : in.runs[0]->stride;
  o << "\n## Frame cost over time (every " << 10 * stride << "th frame)\n\n| frame | time s |";
  for (const auto& n : in.run_names) o << " " << n << " predicted | " << n << " measured | " << n << " switches |";
  o << "\n|---|---|";
  for (size_t r = 0; r < in.runs.size(); ++r) o << "---|---|---|";
  o << "\n";
  const size_t points = in.runs.empty() ? 0 : in.runs[0]->points.size();
  for (size_t i = 0; i < points; i += 10) {
    o << "| " << in.runs[0]->points[i].frame << " | " << num(in.runs[0]->points[i].time_s, 2) << " |";
    for (const ReplayRunDigest* run : in.runs) {
      const ReplayRunDigest::Point& f = run->points[std::min(i, run->points.size() - 1)];
      o << " " << num(f.predicted_ms) << " | " << (f.has_measured ? num(f.measured_ms) : std::string("-")) << " | " << f.switches << " |";
    }
    o << "\n";
  }

  // runs made with --visibility: what occlusion saved (docs/VISIBILITY.md)
  bool any_visibility = false;
  for (const ReplayRunDigest* run : in.runs) any_visibility = any_visibility || run->summary.summary().visibility_frames > 0;
  if (any_visibility) {
    o << "\n## Occlusion and focus\n\n"
         "Hidden objects read a visible fraction below 0.05 from the Embree occlusion estimate. The saving is the "
         "predicted cost a selection without visibility (same parameters, focus and cost model) spends on them, "
         "minus what the selection with visibility spends on them.\n\n"
         "| run | frames | hidden objects (mean share) | predicted ms on hidden objects without occlusion | "
         "occlusion saved ms / frame | frames whose pick hit an object |\n|---|---|---|---|---|---|\n";
    for (size_t r = 0; r < in.runs.size(); ++r) {
      const ReplaySummary s = in.runs[r]->summary.summary();
      if (!s.visibility_frames) continue;
      o << "| " << in.run_names[r] << " | " << s.visibility_frames << " | " << num(100.0 * s.mean_hidden_share, 1) << " % | "
        << num(s.mean_hidden_cost_without_ms) << " | " << num(s.mean_occlusion_saved_ms) << " | " << s.pick_frames << " |\n";
    }
  }

  // plots beside the report
  const size_t slash = md_path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? std::string() : md_path.substr(0, slash + 1);
  std::string stem = md_path.substr(dir.size());
  if (stem.size() > 3 && stem.substr(stem.size() - 3) == ".md") stem.resize(stem.size() - 3);
  std::vector<eval::PlotSeries> cost, levels, switches;
  int color = 0;
  for (size_t r = 0; r < in.runs.size(); ++r) {
    const ReplayRunDigest& run = *in.runs[r];
    eval::PlotSeries pred, meas, budget;
    pred.name = in.run_names[r] + " predicted";
    meas.name = in.run_names[r] + " measured";
    budget.name = in.run_names[r] + " budget";
    pred.markers = meas.markers = budget.markers = false;
    for (const ReplayRunDigest::Point& f : run.points) {
      pred.x.push_back(f.time_s);
      pred.y.push_back(f.predicted_ms);
      if (f.has_measured) {
        meas.x.push_back(f.time_s);
        meas.y.push_back(f.measured_ms);
      }
      if (f.has_budget) {
        budget.x.push_back(f.time_s);
        budget.y.push_back(f.budget_ms);
      }
    }
    pred.color = eval::seriesColor(color++);
    meas.color = eval::seriesColor(color++);
    budget.color = eval::seriesColor(color++);
    cost.push_back(pred);
    if (!meas.x.empty()) cost.push_back(meas);
    if (!budget.x.empty()) cost.push_back(budget);
    const ReplaySummary s = run.summary.summary();
    size_t total = 0;
    for (size_t c : s.level_histogram) total += c;
    eval::PlotSeries h;
    h.name = in.run_names[r];
    h.color = eval::seriesColor(static_cast<int>(r));
    for (size_t k = 0; k < s.level_histogram.size(); ++k) {
      h.x.push_back(static_cast<double>(k) - 1.0);
      h.y.push_back(total ? 100.0 * s.level_histogram[k] / total : 0.0);
    }
    levels.push_back(h);
    // switches per second, in whole-second bins (the first frame's initial choice left out)
    const std::map<long, double>& bins = run.switches_per_second;
    eval::PlotSeries sw;
    sw.name = in.run_names[r];
    sw.color = eval::seriesColor(static_cast<int>(r));
    for (const auto& b : bins) {
      sw.x.push_back(static_cast<double>(b.first) + 0.5);
      sw.y.push_back(b.second);
    }
    switches.push_back(sw);
  }
  std::vector<std::pair<std::string, std::string>> images;
  auto plot = [&](const std::vector<eval::PlotSeries>& series, const char* suffix, const char* title, const char* xl,
                  const char* yl) -> Error {
    bool any = false;
    for (const auto& s : series) any = any || !s.x.empty();
    if (!any) return Error();
    eval::PlotParams p;
    p.title = title;
    p.x_label = xl;
    p.y_label = yl;
    const std::string file = stem + suffix;
    if (Error e = eval::writePlotPng(dir + file, series, p); !e.ok()) return e;
    images.push_back({title, file});
    return Error();
  };
  if (Error e = plot(cost, "_cost.png", "frame cost vs budget", "time (s)", "ms"); !e.ok()) return e;
  if (Error e = plot(levels, "_levels.png", "level histogram (-1 = not drawn)", "level", "% of object-frames"); !e.ok()) return e;
  if (Error e = plot(switches, "_switches.png", "level switches per second", "time (s)", "switches"); !e.ok()) return e;
  if (!images.empty()) {
    o << "\n## Plots\n\n";
    for (const auto& im : images) o << "![" << im.first << "](" << im.second << ")\n\n";
  }
  if (!in.extra_sections.empty()) o << "\n" << in.extra_sections;

  const std::string text = o.str();
  return writeFileAtomic(md_path, text.data(), text.size());
}

}  // namespace scenelod::tool
