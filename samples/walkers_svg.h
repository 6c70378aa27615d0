// SPDX-License-Identifier: MIT
// walkers_svg.h: the top-down picture `walkers --svg FILE` draws of a run.
//
// Looking down the -Y axis (x to the right, z downwards): the level's
// upward-facing triangles, the floors (walkable: within 45 degrees of
// horizontal) grey, lighter the higher they are (a wall's top is a high
// floor), the steeper ones (slopes too steep to walk) a brown, darker the
// steeper, and vertical ones (walls) dark brown lines; triangles facing down
// (ceilings, undersides) are left out, so they hide nothing. Triangles
// are painted lowest first, so an upper floor covers what lies below it.
// On top: every agent's path (one polyline per agent, a point kept each time
// the agent has moved 0.25 m from the last one kept), its start, and the
// events of the run: refused moves (red crosses), agents that fell out of the
// level (a magenta ring where each crossed the level's lowest point) and
// agent-frames inside a solid (orange dots; with --brushes). Events of one
// kind in the same 5 cm square are drawn once; the counts in the legend and in
// the <desc> element are of all of them.
//
// Size: the level is written as one <path> per shade (16 of them), a
// triangle a few tens of bytes; the arena's picture is about 40 kB, a
// shared level of 9,000 triangles about 400 kB.
#pragma once

#include <bspf/movement.h>
#include <bspf/world.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <set>
#include <span>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace bspf::walkers {

/// Records a run frame by frame, then writes it as SVG text.
class SvgRecorder {
 public:
  static constexpr int kWallShade = 16;

  explicit SvgRecorder(const World& world) : world_(&world) {}

  /// After every frame: the bodies, their reports (parallel to them), and
  /// for each body whether its centre is inside a solid (empty without
  /// brushes).
  void frame(std::span<const Body> bodies, std::span<const StepReport> reports,
             const std::vector<bool>& insideSolid) {
    const float floorY = world_->blob().bounds_min()->y();
    insideChecked_ = insideChecked_ || !insideSolid.empty();
    if (paths_.empty()) {
      paths_.resize(bodies.size());
      fell_.assign(bodies.size(), false);
      last_.resize(bodies.size());
    }
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const Vec3& p = bodies[i].position;
      std::vector<std::pair<float, float>>& path = paths_[i];
      if (path.empty() ||
          std::hypot(p.x() - path.back().first, p.z() - path.back().second) >= 0.25f) {
        path.emplace_back(p.x(), p.z());
      }
      last_[i] = {p.x(), p.z()};
      if (i < reports.size() && reports[i].refused) add(refused_, p, refusedCount_);
      if (i < insideSolid.size() && insideSolid[i]) add(inside_, p, insideCount_);
      if (!fell_[i] && p.y() < floorY) {
        fell_[i] = true;
        add(fellOut_, p, fellOutCount_);
      }
    }
  }

  long long refusedMoves() const { return refusedCount_; }
  long long fellOut() const { return fellOutCount_; }
  long long insideSolid() const { return insideCount_; }

  /// The picture, `title` in its heading.
  std::string svg(const std::string& title) const {
    const schema::World& blob = world_->blob();
    const float minX = blob.bounds_min()->x(), maxX = blob.bounds_max()->x();
    const float minZ = blob.bounds_min()->z(), maxZ = blob.bounds_max()->z();
    const float minY = blob.bounds_min()->y(), maxY = blob.bounds_max()->y();
    const float width = std::max(maxX - minX, 1.0f), depth = std::max(maxZ - minZ, 1.0f);
    const float margin = 0.03f * std::max(width, depth);
    const float legend = 0.15f * std::max(width, depth);  // room for the legend below
    const float unit = std::max(width, depth) / 400;      // a line's width, metres
    const double pixels = 1000.0 / std::max(width, depth);
    std::string out;
    appendf(out,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
            "viewBox=\"%.2f %.2f %.2f %.2f\">\n",
            (width + 2 * margin) * pixels, (depth + 2 * margin + legend) * pixels, minX - margin,
            minZ - margin, width + 2 * margin, depth + 2 * margin + legend);
    // Without brushes nothing was checked: the picture says so, not 0.
    const std::string inside = insideChecked_ ? std::to_string(insideCount_) : "not checked";
    appendf(out,
            "<desc>walkers top-down view: %zu agents, refused moves %lld, fell out %lld, "
            "inside-solid agent-frames %s</desc>\n",
            paths_.size(), refusedCount_, fellOutCount_, inside.c_str());
    appendf(out, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"#ffffff\"/>\n",
            minX - margin, minZ - margin, width + 2 * margin, depth + 2 * margin + legend);

    // Triangles by shade, lowest first within the painting order.
    struct Shaded {
      float height;
      int shade;  // 0-7 floors (by height), 8-15 steep (by slope), kWallShade vertical
      std::uint32_t triangle;
    };
    std::vector<Shaded> shaded;
    const float walkable = std::cos(45.0f * 3.14159265f / 180);
    for (std::uint32_t t = 0; t < world_->triangles().size(); ++t) {
      const schema::Vec3& n = world_->trianglePlanes()[t].face().normal();
      if (n.y() < -0.01f) continue;  // facing down: hidden from above
      const auto [a, b, c] = corners(t);
      const float top = std::max({a.y(), b.y(), c.y()});
      int shade;
      if (n.y() >= walkable)
        shade = std::clamp(int(8 * (top - minY) / std::max(maxY - minY, 1e-3f)), 0, 7);
      else if (n.y() > 0.01f)
        shade = 8 + std::clamp(int(8 * (1 - n.y() / walkable)), 0, 7);
      else
        shade = kWallShade;  // vertical: a line seen from above
      shaded.push_back({top, shade, t});
    }
    std::stable_sort(shaded.begin(), shaded.end(),
                     [](const Shaded& a, const Shaded& b) { return a.height < b.height; });
    // One path per shade would paint all of a shade at once, out of height
    // order; so runs of triangles are grouped into height bands of 1/8 of
    // the level's height, and each band drawn as one path per shade.
    std::map<std::pair<int, int>, std::string> bands;  // (band, shade) -> path data
    for (const Shaded& s : shaded) {
      const int band =
          std::clamp(int(16 * (s.height - minY) / std::max(maxY - minY, 1e-3f)), 0, 15);
      const auto [a, b, c] = corners(s.triangle);
      std::string& d = bands[{band, s.shade}];
      if (s.shade == kWallShade) {  // seen from above, a segment: its two ends
        const Vec3* ends[2] = {&a, &b};
        float longest = -1;
        for (const auto& [p, q] : {std::pair(&a, &b), std::pair(&b, &c), std::pair(&a, &c)}) {
          const float length = std::hypot(p->x() - q->x(), p->z() - q->z());
          if (length > longest) longest = length, ends[0] = p, ends[1] = q;
        }
        appendf(d, "M%.2f %.2fL%.2f %.2f", ends[0]->x(), ends[0]->z(), ends[1]->x(), ends[1]->z());
      } else {
        appendf(d, "M%.2f %.2fL%.2f %.2fL%.2f %.2fZ", a.x(), a.z(), b.x(), b.z(), c.x(), c.z());
      }
    }
    for (const auto& [key, d] : bands) {
      const int shade = key.second;
      if (shade == kWallShade) {  // outlines only: a vertical triangle has no area from above
        appendf(out,
                "<path fill=\"none\" stroke=\"#5a3214\" stroke-width=\"%.3f\" "
                "stroke-linecap=\"round\" d=\"",
                unit);
      } else {
        int r, g, b;
        if (shade < 8) {  // floors: grey from 150 (low) to 234 (high)
          r = g = b = 150 + shade * 12;
        } else {  // steep: brown, darker the steeper
          const int k = shade - 8;
          r = 190 - 12 * k;
          g = 140 - 10 * k;
          b = 100 - 8 * k;
        }
        appendf(out,
                "<path fill=\"#%02x%02x%02x\" stroke=\"#%02x%02x%02x\" stroke-width=\"%.3f\" "
                "d=\"",
                r, g, b, r, g, b, 0.3 * unit);
      }
      out += d;
      out += "\"/>\n";
    }

    // Paths, one colour per agent (hues around the wheel).
    for (std::size_t i = 0; i < paths_.size(); ++i) {
      std::vector<std::pair<float, float>> path = paths_[i];
      if (path.back() != last_[i]) path.push_back(last_[i]);
      const std::string colour = hue(double(i) / double(std::max<std::size_t>(paths_.size(), 1)));
      appendf(out, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.3f\" fill=\"%s\"/>\n", path[0].first,
              path[0].second, 1.5 * unit, colour.c_str());
      appendf(out,
              "<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"%.3f\" "
              "stroke-opacity=\"0.8\" points=\"",
              colour.c_str(), unit);
      for (const auto& [x, z] : path) appendf(out, "%.2f,%.2f ", x, z);
      out += "\"/>\n";
    }

    // Events.
    if (!refused_.empty()) {
      out += "<path fill=\"none\" stroke=\"#e00000\" stroke-width=\"" + number(unit) + "\" d=\"";
      for (const auto& [x, z] : refused_)
        appendf(out, "M%.2f %.2fl%.3f %.3fm0 %.3fl%.3f %.3f", x - 2 * unit, z - 2 * unit, 4 * unit,
                4 * unit, -4 * unit, -4 * unit, 4 * unit);
      out += "\"/>\n";
    }
    for (const auto& [x, z] : fellOut_)
      appendf(out,
              "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.3f\" fill=\"none\" stroke=\"#d000d0\" "
              "stroke-width=\"%.3f\"/>\n",
              x, z, 4 * unit, 1.5 * unit);
    for (const auto& [x, z] : inside_)
      appendf(out, "<circle cx=\"%.2f\" cy=\"%.2f\" r=\"%.3f\" fill=\"#ff8c00\"/>\n", x, z,
              2.5 * unit);

    // Legend, below the level.
    const float y0 = maxZ + margin + 0.25f * legend, x0 = minX;
    const float font = std::max(width, depth) / 50;
    appendf(out,
            "<g font-family=\"sans-serif\" font-size=\"%.2f\" fill=\"#000000\">\n"
            "<text x=\"%.2f\" y=\"%.2f\">%s</text>\n",
            font, x0, y0, escape(title).c_str());
    const float line = 1.5f * font;
    appendf(out,
            "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"#969696\"/>"
            "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"#eaeaea\"/>"
            "<text x=\"%.2f\" y=\"%.2f\">floor, low to high</text>\n",
            x0, y0 + 0.5f * line, font, font, x0 + font, y0 + 0.5f * line, font, font,
            x0 + 2.4f * font, y0 + line + 0.2f * font);
    appendf(out,
            "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\" fill=\"#a67850\"/>"
            "<text x=\"%.2f\" y=\"%.2f\">too steep</text>"
            "<path d=\"M%.2f %.2fh%.2f\" stroke=\"#5a3214\" stroke-width=\"%.3f\"/>"
            "<text x=\"%.2f\" y=\"%.2f\">wall</text>\n",
            x0 + 12 * font, y0 + 0.5f * line, font, font, x0 + 13.4f * font,
            y0 + line + 0.2f * font, x0 + 19 * font, y0 + line - 0.1f * font, font, double(unit),
            x0 + 20.4f * font, y0 + line + 0.2f * font);
    appendf(out, "<text x=\"%.2f\" y=\"%.2f\">lines: agents' paths (dot: start)</text>\n", x0,
            y0 + 2 * line + 0.2f * font);
    appendf(out,
            "<text x=\"%.2f\" y=\"%.2f\"><tspan fill=\"#e00000\">x refused moves %lld</tspan>; "
            "<tspan fill=\"#d000d0\">o fell out %lld</tspan>; "
            "<tspan fill=\"#ff8c00\">&#8226; inside a solid %s</tspan></text>\n</g>\n",
            x0, y0 + 3 * line + 0.2f * font, refusedCount_, fellOutCount_,
            (insideChecked_ ? inside : std::string("not checked (no --brushes)")).c_str());
    out += "</svg>\n";
    return out;
  }

 private:
  std::array<Vec3, 3> corners(std::uint32_t t) const {
    const schema::Triangle& tri = world_->triangles()[t];
    return {toVec3(world_->vertices()[tri.v0()]), toVec3(world_->vertices()[tri.v1()]),
            toVec3(world_->vertices()[tri.v2()])};
  }

  // Counts the event; keeps its point unless one of the same kind in the
  // same 5 cm square is kept.
  void add(std::vector<std::pair<float, float>>& points, const Vec3& p, long long& count) {
    ++count;
    const auto cell = std::make_tuple(&points, std::int64_t(std::floor(p.x() / 0.05f)),
                                      std::int64_t(std::floor(p.z() / 0.05f)));
    if (seen_.insert(cell).second) points.emplace_back(p.x(), p.z());
  }

  template <typename... Args>
  static void appendf(std::string& out, const char* format, Args... args) {
    char buffer[512];
    const int n = std::snprintf(buffer, sizeof buffer, format, args...);
    if (n < int(sizeof buffer)) {
      out.append(buffer, std::size_t(std::max(n, 0)));
    } else {
      std::string big(std::size_t(n) + 1, '\0');
      std::snprintf(big.data(), big.size(), format, args...);
      big.resize(std::size_t(n));
      out += big;
    }
  }

  static std::string number(double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3f", v);
    return text;
  }

  // A saturated colour at `turn` (0 to 1) around the hue wheel.
  static std::string hue(double turn) {
    const double h = 6 * (turn - std::floor(turn));
    const double x = 1 - std::abs(std::fmod(h, 2.0) - 1);
    double r = 0, g = 0, b = 0;
    switch (int(h)) {
      case 0: r = 1, g = x; break;
      case 1: r = x, g = 1; break;
      case 2: g = 1, b = x; break;
      case 3: g = x, b = 1; break;
      case 4: r = x, b = 1; break;
      default: r = 1, b = x; break;
    }
    char text[8];
    std::snprintf(text, sizeof text, "#%02x%02x%02x", int(40 + 160 * r), int(40 + 160 * g),
                  int(40 + 160 * b));
    return text;
  }

  static std::string escape(const std::string& s) {
    std::string out;
    for (const char c : s) {
      if (c == '&')
        out += "&amp;";
      else if (c == '<')
        out += "&lt;";
      else if (c == '>')
        out += "&gt;";
      else if (c == '"')
        out += "&quot;";
      else
        out += c;
    }
    return out;
  }

  const World* world_;
  std::vector<std::vector<std::pair<float, float>>> paths_;
  std::vector<std::pair<float, float>> last_;
  std::vector<bool> fell_;
  std::vector<std::pair<float, float>> refused_, fellOut_, inside_;
  long long refusedCount_ = 0, fellOutCount_ = 0, insideCount_ = 0;
  bool insideChecked_ = false;  // some frame came with brush results
  std::set<std::tuple<const void*, std::int64_t, std::int64_t>> seen_;
};

}  // namespace bspf::walkers
