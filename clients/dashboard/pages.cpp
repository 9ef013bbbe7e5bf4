#include "clients/dashboard/pages.h"

#include <fmt/format.h>

#include <chrono>
#include <ctime>

#include "plot/xml_escape.h"

namespace pnp::dashboard {
namespace {

using plot::escape_xml;

constexpr const char* kStyle = R"(<style>
body{font-family:sans-serif;margin:1.5em;color:#222}
table{border-collapse:collapse;margin:.5em 0 1.5em}
th,td{border-bottom:1px solid #ddd;padding:.25em .6em;text-align:left;font-size:14px}
th{background:#f3f3f3}
.state-reached{color:#2ca02c}.state-not-reached{color:#b8860b}.state-failed{color:#d62728}.state-running{color:#1f77b4}
.ok{color:#2ca02c}.bad{color:#d62728}
nav a{margin-right:1em}
svg{margin:.5em 0}
</style>)";

std::string page(const std::string& title, const std::string& body) {
  return fmt::format(
      "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{} &#8212; "
      "pnp</title>{}</head><body><nav><a href=\"/\">runs</a><a "
      "href=\"/episodes\">episodes</a></nav><h1>{}</h1>\n{}</body></html>\n",
      escape_xml(title), kStyle, escape_xml(title), body);
}

std::string when(store::Millis ms) {
  if (ms <= 0) return "";
  const std::time_t seconds = static_cast<std::time_t>(ms / 1000);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char text[32];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &utc);
  return std::string(text) + " UTC";
}

std::string percent(double fraction) {
  return fmt::format("{:.1f}%", 100 * fraction);
}

// Where a run's wall time went, by phase: the parts of it that have ended (the store sums a
// run's parts as each trainer stops).
std::string wall_breakdown_html(const WallBreakdown& w) {
  if (!(w.total_s > 0)) {
    return "<p id=\"wall-breakdown\">Where its time went: nothing recorded yet (each trainer "
           "records its part as it stops).</p>\n";
  }
  const auto phase = [&](const char* name, double seconds) {
    return fmt::format("{} {:.1f} s ({})", name, seconds, percent(seconds / w.total_s));
  };
  return fmt::format(
      "<p id=\"wall-breakdown\">Where its time went ({:.1f} s in the parts that have ended): "
      "{}, {}, {}, {}, {}.</p>\n",
      w.total_s, phase("rollouts", w.rollout_s), phase("updates", w.update_s),
      phase("evaluation", w.eval_s), phase("checkpoints and store writes", w.report_s),
      phase("other", w.other_s));
}

}  // namespace

std::string overview_page(const std::vector<store::RunRecord>& runs,
                          const std::vector<store::Promotion>& promotions,
                          const ServingView& serving) {
  std::string body = "<h2>Served</h2>\n";
  if (!serving.error.empty()) {
    body += fmt::format("<p class=\"bad\" id=\"serving\">inference service: {}</p>\n",
                        escape_xml(serving.error));
  } else {
    body += fmt::format(
        "<p id=\"serving\" data-ready=\"{}\">{} {}</p>\n", serving.ready ? 1 : 0,
        serving.ready ? "<span class=\"ok\">ready</span>" : "<span class=\"bad\">not ready</span>",
        escape_xml(serving.world));
  }
  body +=
      "<table "
      "id=\"promotions\"><tr><th>role</th><th>checkpoint</th><th>promoted</th><th>by</th></tr>\n";
  for (const auto& p : promotions)
    body +=
        fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", escape_xml(p.role),
                    p.checkpoint_id, when(p.promoted_ms), escape_xml(p.promoted_by));
  body +=
      "</table>\n<h2>Runs</h2>\n<table id=\"runs\"><tr><th>run</th><th>role</th>"
      "<th>algorithm</th><th>robot / object</th><th>seed</th><th>outcome</th><th>steps</th>"
      "<th>success</th><th>target reached at</th><th>created</th></tr>\n";
  for (const auto& r : runs) {
    const std::string state(store::run_outcome(r.state, r.reached));
    body += fmt::format(
        "<tr class=\"run\" data-run=\"{}\"><td><a href=\"/runs/{}\">{}</a></td><td>{}</td>"
        "<td>{}</td><td>{} / {}</td><td>{}</td><td class=\"state-{}\">{}</td><td>{}</td>"
        "<td>{}</td><td>{}</td><td>{}</td></tr>\n",
        r.id, r.id, r.id, escape_xml(r.spec.role), escape_xml(r.spec.algorithm),
        escape_xml(r.spec.robot), escape_xml(r.spec.object), r.spec.seed, state, state, r.env_steps,
        percent(r.last_success), r.steps_to_target ? std::to_string(*r.steps_to_target) : "",
        when(r.created_ms));
  }
  body += "</table>\n";
  return page("pnp platform", body);
}

std::string run_page(const store::RunRecord& run,
                     const std::vector<store::CheckpointInfo>& checkpoints) {
  std::string body = fmt::format(
      "<p id=\"run-state\" data-run=\"{}\">{} {} on {} / {}, seed {}: <b "
      "id=\"state\">{}</b>, <span id=\"steps\">{}</span> training steps, <span "
      "id=\"wall\">&#8212;</span> of training</p>\n"
      "<div id=\"curve\" data-points=\"0\">loading the learning curve&#8230;</div>\n",
      run.id, escape_xml(run.spec.role), escape_xml(run.spec.algorithm), escape_xml(run.spec.robot),
      escape_xml(run.spec.object), run.spec.seed, store::run_outcome(run.state, run.reached),
      run.env_steps);
  if (!run.error.empty()) body += fmt::format("<p class=\"bad\">{}</p>\n", escape_xml(run.error));
  body += wall_breakdown_html(run.wall);
  body +=
      "<h2>Checkpoints</h2>\n<table id=\"checkpoints\"><tr><th>checkpoint</th><th>steps</th>"
      "<th>evaluated success</th><th>size</th><th>created</th></tr>\n";
  for (const auto& c : checkpoints)
    body +=
        fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{} kB</td><td>{}</td></tr>\n", c.id,
                    c.env_steps, c.unevaluated ? "not evaluated" : percent(c.eval_success),
                    c.size_bytes / 1024, when(c.created_ms));
  body += "</table>\n<details><summary>configuration</summary><pre>" +
          escape_xml(nlohmann::json::parse(run.spec.config_json, nullptr, false).dump(2)) +
          "</pre></details>\n";
  body += "<script>\n" + live_curve_script(1000) + "</script>\n";
  return page("run " + std::to_string(run.id), body);
}

std::string episodes_page(const PlayedEpisodes& played) {
  std::string body = fmt::format(
      "<p id=\"summary\" data-episodes=\"{}\" data-successes=\"{}\">{} of {} held-out episodes "
      "placed ({}/{}/{}, {} hand, seed {}): the served hierarchy, through the simulation and "
      "inference "
      "services. The gripper's path is coloured by the subtask the choreographer chose.</p>\n"
      "<form><label>episodes <input name=\"count\" value=\"{}\" size=\"3\"></label> "
      "<label>seed <input name=\"seed\" value=\"{}\" size=\"8\"></label> "
      "<button>play</button></form>\n",
      played.episodes.size(), played.successes, played.successes, played.episodes.size(),
      escape_xml(played.world.world), escape_xml(played.world.robot),
      escape_xml(played.world.object), escape_xml(played.world.actuation), played.seed,
      played.episodes.size(), played.seed);
  for (const auto& e : played.episodes) body += "<div>" + plot::episode_view_svg(e) + "</div>\n";
  return page("Episodes", body);
}

std::string error_page(int status, const std::string& message) {
  return page(fmt::format("Error {}", status),
              "<p class=\"bad\" id=\"error\">" + escape_xml(message) + "</p>\n");
}

std::string access_page(int status, const std::string& message) {
  return page(status == 401 ? "Sign in" : "Not allowed",
              "<p class=\"bad\" id=\"error\">" + escape_xml(message) +
                  "</p>\n<p>This dashboard shows the platform to readers (the platform's "
                  "authorization policy): <a href=\"/login\">sign in with a reader's "
                  "token</a>.</p>\n");
}

std::string login_page(const std::string& error, const std::string& nonce) {
  std::string body;
  if (!error.empty()) body += "<p class=\"bad\" id=\"error\">" + escape_xml(error) + "</p>\n";
  body += "<form method=\"post\" action=\"/login\"><input type=\"hidden\" name=\"csrf\" value=\"" +
          escape_xml(nonce) +
          "\"><label>reader's token <input "
          "type=\"password\" name=\"token\" size=\"66\" autocomplete=\"off\"></label> "
          "<button>sign in</button></form>\n<p>The token stays on the server: the browser keeps "
          "only a session id (HttpOnly, this site only) until it expires or you sign out (POST "
          "/logout). A token that may operate the platform or move the arm is refused here.</p>\n";
  return page("Sign in", body);
}

nlohmann::json run_json(const store::RunRecord& run,
                        const std::vector<store::MetricPoint>& metrics) {
  nlohmann::json points = nlohmann::json::array();
  for (const auto& m : metrics)
    points.push_back({{"env_steps", m.env_steps},
                      {"wall_s", m.wall_s},
                      {"task_success", m.task_success},
                      {"subtask_success", m.subtask_success},
                      {"stop_score", m.stop_score ? nlohmann::json(*m.stop_score) : nullptr}});
  return {{"run_id", run.id},
          {"role", run.spec.role},
          {"state", store::run_state_name(run.state)},
          {"outcome", store::run_outcome(run.state, run.reached)},
          {"env_steps", run.env_steps},
          {"last_success", run.last_success},
          {"points", points}};
}

std::string live_curve_script(int poll_ms) {
  // Plain ES2017, no library: the page works offline and in any browser.
  return fmt::format(R"js(
const runId = document.getElementById('run-state').dataset.run;
const series = [['task_success', '#1f77b4', 'task success', ''],
                ['subtask_success', '#ff7f0e', 'subtask success', ''],
                ['stop_score', '#2ca02c', 'stop score', '5 4']];
function draw(run) {{
  const W = 640, H = 320, L = 50, R = 20, T = 36, B = 40;  // the legend above the plot
  const pts = run.points;
  const maxX = Math.max(1, ...pts.map(p => p.env_steps));
  const x = v => L + (W - L - R) * v / maxX, y = v => T + (H - T - B) * (1 - v);
  let svg = `<svg xmlns="http://www.w3.org/2000/svg" class="curve" width="${{W}}" height="${{H}}">`;
  svg += `<rect x="${{L}}" y="${{T}}" width="${{W - L - R}}" height="${{H - T - B}}" fill="#fafafa" stroke="#999"/>`;
  for (const g of [0, 0.5, 0.95, 1]) {{
    svg += `<line x1="${{L}}" x2="${{W - R}}" y1="${{y(g)}}" y2="${{y(g)}}" stroke="#ddd"/>`;
    svg += `<text x="${{L - 6}}" y="${{y(g) + 4}}" font-size="11" text-anchor="end">${{g}}</text>`;
  }}
  for (const t of [0, maxX / 2, maxX]) {{
    svg += `<text x="${{x(t)}}" y="${{H - B + 14}}" font-size="11" text-anchor="middle">${{Math.round(t)}}</text>`;
  }}
  svg += `<text x="${{(L + W - R) / 2}}" y="${{H - 8}}" font-size="12" text-anchor="middle">training steps</text>`;
  series.forEach(([key, colour, label, dash], i) => {{
    const own = pts.filter(p => p[key] !== null);
    const line = own.map(p => `${{x(p.env_steps).toFixed(1)}},${{y(p[key]).toFixed(1)}}`).join(' ');
    svg += `<polyline class="series ${{key}}" data-points="${{own.length}}" points="${{line}}" fill="none" stroke="${{colour}}" stroke-width="2" stroke-dasharray="${{dash}}"/>`;
    for (const p of own) svg += `<circle cx="${{x(p.env_steps).toFixed(1)}}" cy="${{y(p[key]).toFixed(1)}}" r="2.5" fill="${{colour}}"/>`;
    svg += `<text class="legend" x="${{L + 10 + 150 * i}}" y="16" font-size="11" fill="${{colour}}">${{label}}</text>`;
  }});
  const box = document.getElementById('curve');
  box.innerHTML = svg + '</svg>';
  box.dataset.points = pts.length;
  document.getElementById('state').textContent = run.outcome;
  document.getElementById('steps').textContent = run.env_steps;
  if (pts.length) document.getElementById('wall').textContent = `${{pts[pts.length - 1].wall_s.toFixed(1)}} s`;
}}
async function refresh() {{
  try {{
    const answer = await fetch(`/api/runs/${{runId}}`);
    if (answer.ok) {{
      const run = await answer.json();
      draw(run);
      if (['succeeded', 'failed', 'cancelled'].includes(run.state)) return;
    }} else if (answer.status >= 400 && answer.status < 500) {{
      // Signed out, not allowed, or the run is gone: asking again will not help.
      document.getElementById('curve').textContent = `stopped updating: HTTP ${{answer.status}}`;
      return;
    }}
  }} catch (e) {{ /* the dashboard restarting: try again */ }}
  setTimeout(refresh, {});
}}
refresh();
)js",
                     poll_ms);
}

}  // namespace pnp::dashboard
