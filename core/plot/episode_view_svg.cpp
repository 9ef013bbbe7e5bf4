#include "plot/episode_view_svg.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "plot/xml_escape.h"

namespace pnp::plot {
namespace {

constexpr double kPanel = 280;  // each view's drawing area, square, in px
constexpr double kMargin = 40;  // around each view (tick numbers and axis labels)
constexpr double kBelow = 32;   // under each view: tick numbers, then the axis label
constexpr double kTitle = 28;   // the title's band
constexpr double kLegend = 24;  // the legend's band
constexpr double kPadding_m = 0.04;

// The world rectangle a view shows, and how it maps to pixels (equal scale on both axes).
struct ViewBox {
  double u0, v0, scale;  // world (u, v) at the panel's bottom-left corner; px per metre
  double left, top;      // the panel's corner in the svg
  double x(double u) const { return left + (u - u0) * scale; }
  double y(double v) const { return top + kPanel - (v - v0) * scale; }
};

ViewBox fit(const EpisodeTrace& t, std::size_t u, std::size_t v, double left, double top) {
  // The goal's whole success circle is in view.
  const double r = t.success_radius_m;
  double lo_u = t.goal[u] - r, hi_u = t.goal[u] + r, lo_v = t.goal[v] - r, hi_v = t.goal[v] + r;
  for (const auto& f : t.frames) {
    for (const auto* p : {&f.gripper, &f.object}) {
      lo_u = std::min(lo_u, (*p)[u]);
      hi_u = std::max(hi_u, (*p)[u]);
      lo_v = std::min(lo_v, (*p)[v]);
      hi_v = std::max(hi_v, (*p)[v]);
    }
  }
  if (v == 2 && t.table_top_z) lo_v = std::min(lo_v, *t.table_top_z);
  const double span = std::max({hi_u - lo_u, hi_v - lo_v, 0.05}) + 2 * kPadding_m;
  const double scale = kPanel / span;
  // Centred: the shorter extent gets the spare room on both sides.
  return {(lo_u + hi_u) / 2 - span / 2, (lo_v + hi_v) / 2 - span / 2, scale, left, top};
}

// A round step giving at most six ticks over `span` metres.
double tick_step(double span) {
  for (const double step : {0.01, 0.02, 0.05, 0.1, 0.2, 0.5})
    if (span / step <= 6) return step;
  return 1.0;
}

// Numbers along both axes of a view (metres, in the world frame): without them a reader
// could not tell a 2 cm miss from a 20 cm one.
void draw_ticks(std::string& out, const ViewBox& box) {
  const double span = kPanel / box.scale;
  const double step = tick_step(span);
  const int decimals = step >= 0.1 ? 1 : 2;
  const auto label = [&](double value) { return fmt::format("{:.{}f}", value, decimals); };
  for (auto k = static_cast<long>(std::ceil(box.u0 / step));
       k <= static_cast<long>(std::floor((box.u0 + span) / step)); ++k) {
    const double u = static_cast<double>(k) * step;
    out += fmt::format(
        R"svg(<text class="tick" x="{:.1f}" y="{:.1f}" font-size="9" text-anchor="middle">{}</text>)svg",
        box.x(u), box.top + kPanel + 11, label(u));
  }
  for (auto k = static_cast<long>(std::ceil(box.v0 / step));
       k <= static_cast<long>(std::floor((box.v0 + span) / step)); ++k) {
    const double v = static_cast<double>(k) * step;
    out += fmt::format(
        R"svg(<text class="tick" x="{:.1f}" y="{:.1f}" font-size="9" text-anchor="end">{}</text>)svg",
        box.left - 3, box.y(v) + 3, label(v));
  }
}

void draw_view(std::string& out, const EpisodeTrace& t, std::size_t u, std::size_t v, double left,
               const char* name, const char* u_label, const char* v_label) {
  const ViewBox box = fit(t, u, v, left, kTitle);
  out += fmt::format(R"svg(<g class="view {}">)svg", name);
  out += fmt::format(
      R"svg(<rect x="{:.1f}" y="{:.1f}" width="{:.1f}" height="{:.1f}" fill="#fafafa" stroke="#999"/>)svg",
      left, kTitle, kPanel, kPanel);
  draw_ticks(out, box);
  out += fmt::format(
      R"svg(<text x="{:.1f}" y="{:.1f}" font-size="11" text-anchor="middle">{} (m)</text>)svg",
      left + kPanel / 2, kTitle + kPanel + 26, u_label);
  out += fmt::format(
      R"svg(<text x="{:.1f}" y="{:.1f}" font-size="11" text-anchor="middle" transform="rotate(-90 {:.1f} {:.1f})">{} (m)</text>)svg",
      left - 30, kTitle + kPanel / 2, left - 30, kTitle + kPanel / 2, v_label);
  if (v == 2 && t.table_top_z) {
    out += fmt::format(
        R"svg(<line class="table" x1="{:.1f}" y1="{:.1f}" x2="{:.1f}" y2="{:.1f}" stroke="#8c564b" stroke-width="2"/>)svg",
        left, box.y(*t.table_top_z), left + kPanel, box.y(*t.table_top_z));
  }
  // The goal and its success radius (a circle in both views: the radius is 3-D).
  out += fmt::format(
      R"svg(<circle class="goal" cx="{:.1f}" cy="{:.1f}" r="{:.1f}" fill="#2ca02c22" stroke="#2ca02c" stroke-dasharray="4 3"/>)svg",
      box.x(t.goal[u]), box.y(t.goal[v]), t.success_radius_m * box.scale);
  out += fmt::format(R"svg(<circle cx="{:.1f}" cy="{:.1f}" r="3" fill="#2ca02c"/>)svg",
                     box.x(t.goal[u]), box.y(t.goal[v]));
  if (!t.frames.empty()) {
    std::string points;
    for (const auto& f : t.frames)
      points += fmt::format("{:.1f},{:.1f} ", box.x(f.object[u]), box.y(f.object[v]));
    out += fmt::format(
        R"svg(<polyline class="object-path" points="{}" fill="none" stroke="#333" stroke-width="1.5" stroke-dasharray="3 2"/>)svg",
        points);
    for (std::size_t k = 1; k < t.frames.size(); ++k) {
      const auto& a = t.frames[k - 1];
      const auto& b = t.frames[k];
      out += fmt::format(
          R"svg(<line class="gripper subtask-{}" x1="{:.1f}" y1="{:.1f}" x2="{:.1f}" y2="{:.1f}" stroke="{}" stroke-width="2.5" stroke-linecap="round"/>)svg",
          subtask_name(b.subtask), box.x(a.gripper[u]), box.y(a.gripper[v]), box.x(b.gripper[u]),
          box.y(b.gripper[v]), subtask_colour(b.subtask));
    }
    const auto& start = t.frames.front();
    out += fmt::format(
        R"svg(<circle class="start" cx="{:.1f}" cy="{:.1f}" r="4" fill="none" stroke="#000"/>)svg",
        box.x(start.gripper[u]), box.y(start.gripper[v]));
    out += fmt::format(
        R"svg(<rect class="object-start" x="{:.1f}" y="{:.1f}" width="7" height="7" fill="#333"/>)svg",
        box.x(start.object[u]) - 3.5, box.y(start.object[v]) - 3.5);
  }
  out += "</g>";
}

}  // namespace

std::string subtask_name(int subtask) {
  switch (subtask) {
    case 0:
      return "approach";
    case 1:
      return "manipulate";
    case 2:
      return "retract";
    default:
      return "none";
  }
}

std::string subtask_colour(int subtask) {
  switch (subtask) {
    case 0:
      return "#1f77b4";
    case 1:
      return "#ff7f0e";
    case 2:
      return "#2ca02c";
    default:
      return "#7f7f7f";
  }
}

std::string episode_view_svg(const EpisodeTrace& t) {
  const double width = 2 * (kPanel + 2 * kMargin);
  const double height = kTitle + kPanel + kBelow + kLegend;
  std::string out = fmt::format(
      R"svg(<svg xmlns="http://www.w3.org/2000/svg" class="episode" data-steps="{}" data-success="{}" width="{:.0f}" height="{:.0f}" viewBox="0 0 {:.0f} {:.0f}" font-family="sans-serif">)svg",
      t.frames.empty() ? 0 : t.frames.size() - 1, t.success ? 1 : 0, width, height, width, height);
  out += fmt::format(
      R"svg(<text x="{:.1f}" y="18" font-size="13" font-weight="bold" fill="{}">{} &#8212; {}</text>)svg",
      kMargin, t.success ? "#2ca02c" : "#d62728", escape_xml(t.title),
      t.success ? "placed" : "not placed");
  draw_view(out, t, 0, 1, kMargin, "top", "x", "y");
  draw_view(out, t, 0, 2, kPanel + 3 * kMargin, "side", "x", "z");
  double x = kMargin;
  const double y = kTitle + kPanel + kBelow + 14;
  for (int s = 0; s < 3; ++s) {
    out += fmt::format(
        R"svg(<line x1="{:.1f}" y1="{:.1f}" x2="{:.1f}" y2="{:.1f}" stroke="{}" stroke-width="3"/><text x="{:.1f}" y="{:.1f}" font-size="11">{}</text>)svg",
        x, y - 4, x + 18, y - 4, subtask_colour(s), x + 22, y, subtask_name(s));
    x += 100;
  }
  out += fmt::format(
      R"svg(<line x1="{:.1f}" y1="{:.1f}" x2="{:.1f}" y2="{:.1f}" stroke="#333" stroke-dasharray="3 2"/><text x="{:.1f}" y="{:.1f}" font-size="11">object</text>)svg",
      x, y - 4, x + 18, y - 4, x + 22, y);
  x += 80;
  out += fmt::format(
      R"svg(<circle cx="{:.1f}" cy="{:.1f}" r="5" fill="#2ca02c22" stroke="#2ca02c" stroke-dasharray="4 3"/><text x="{:.1f}" y="{:.1f}" font-size="11">goal ({:.0f} cm)</text>)svg",
      x + 6, y - 4, x + 16, y, t.success_radius_m * 100);
  out += "</svg>\n";
  return out;
}

}  // namespace pnp::plot
