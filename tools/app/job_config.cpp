// kdmesh — batch files: YAML -> MeshJob list, every error naming file:line and key.
// yaml-cpp stays in this file.
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "tools/app/job_config.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <utility>

#include "core/error.h"
#include "core/memory_amount.h"
#include "io/file_io.h"
#include "io/surface_io.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/surface/surface_repair.h"
#include "tools/app/job_paths.h"

namespace kdmesh {

namespace fs = std::filesystem;

std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diag = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::size_t(-1);
  for (const std::string& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) best_d = d, best = c;
  }
  // "Reasonably close": at most half the longer word's letters differ (and at least 1 allowed).
  const std::size_t limit = std::max<std::size_t>(1, std::max(word.size(), best.size()) / 2);
  return best_d <= limit ? best : std::string();
}

namespace {

const std::vector<std::string> kTopKeys = {"defaults", "jobs"};
const std::vector<std::string> kJobKeys = {"name",        "input", "scale", "size",  "min_size",
                                           "gradation",   "sharp_angle",    "zones", "order",
                                           "seed",        "check", "max_memory", "repair", "groups",
                                           "patch_groups", "element_order", "msh_version", "improve", "output",
                                           "curvature_angle", "chordal_deviation", "auto_creases", "thickness_layers",
                                           "tolerance", "max_refinements", "timeout", "bodies"};
const std::vector<std::string> kBodyKeys = {"name", "input"};
const std::vector<std::string> kZoneTypes = {"sharp_edges", "polyline", "segment", "plane",
                                             "point",       "box",      "ball"};
const std::vector<std::string> kOutputKeys = {"vtu", "summary", "nodes", "msh", "inp", "mesh", "boundary_vtu", "xdmf", "exodus"};
const std::vector<std::string> kGroupKeys = {"name", "dim", "zone", "point", "box"};
const std::vector<std::string> kChecks = {"tetgen", "delaunay"};

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const std::string& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

/// The keys a zone of `type` takes besides type, size and name.
std::vector<std::string> zone_keys(const std::string& type) {
  if (type == "sharp_edges") return {"angle"};
  if (type == "polyline") return {"points"};
  if (type == "segment") return {"from", "to"};
  if (type == "plane") return {"origin", "normal"};
  if (type == "point") return {"at"};
  if (type == "box") return {"min", "max"};
  return {"center", "radius"};  // ball
}

/// `s` with control bytes (and DEL) shown as \xNN, so that no message echoes raw control
/// bytes of a hostile file to the terminal.
std::string printable(const std::string& s) {
  std::string out;
  for (const char ch : s) {
    const unsigned char c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f) {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

/// The one place that builds an InputError.
[[noreturn]] void throw_input(const std::string& file, std::uint64_t line, const std::string& msg) {
  throw InputError(printable(file), line, printable(msg));
}

std::uint64_t line_of(const YAML::Node& n) {
  const int l = n.Mark().line;
  return l >= 0 ? std::uint64_t(l) + 1 : 0;
}

std::string describe(const YAML::Node& n) {
  if (!n.IsDefined() || n.IsNull()) return "nothing";
  if (n.IsMap()) return "a mapping";
  if (n.IsSequence()) return "a list";
  return "'" + n.Scalar() + "'";
}

/// One mapping entry: its key node (for the line) and value.
struct Entry {
  YAML::Node key, value;
};

class Loader {
 public:
  Loader(std::string file, fs::path base_dir, fs::path out_dir, bool allow_outside, double zone_limit)
      : file_(std::move(file)),
        base_(std::move(base_dir)),
        out_(std::move(out_dir)),
        allow_outside_(allow_outside),
        zone_limit_(zone_limit) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& msg) const {
    throw_input(file_, line_of(at), msg);
  }

  /// The entries of a mapping, refusing duplicate and unknown keys (with a suggestion).
  std::map<std::string, Entry> entries(const YAML::Node& map, const std::vector<std::string>& valid,
                                       const std::string& where) const {
    if (!map.IsMap()) fail(map, where + ": expected a mapping, got " + describe(map));
    std::map<std::string, Entry> out;
    for (const auto& kv : map) {
      if (!kv.first.IsScalar()) fail(kv.first, where + ": keys must be plain names");
      const std::string key = kv.first.Scalar();
      if (std::find(valid.begin(), valid.end(), key) == valid.end()) {
        const std::string near = closest_match(key, valid);
        fail(kv.first, where + ": unknown key '" + key + "'" +
                           (near.empty() ? "" : " (did you mean '" + near + "'?)") +
                           "; valid keys: " + join(valid));
      }
      if (out.count(key)) fail(kv.first, where + ": duplicate key '" + key + "'");
      out[key] = {kv.first, kv.second};
    }
    return out;
  }

  double number(const YAML::Node& v, const std::string& what) const {
    double d = 0;
    if (!v.IsScalar() || v.Tag() == "!" || !YAML::convert<double>::decode(v, d))
      fail(v, what + ": expected a number, got " + describe(v));
    if (!std::isfinite(d)) fail(v, what + ": expected a finite number, got " + describe(v));
    return d;
  }

  double positive(const YAML::Node& v, const std::string& what) const {
    const double d = number(v, what);
    if (!(d > 0)) fail(v, what + ": must be > 0, got " + v.Scalar());
    return d;
  }

  std::uint64_t unsigned_integer(const YAML::Node& v, const std::string& what) const {
    const std::string s = v.IsScalar() && v.Tag() != "!" ? v.Scalar() : std::string();
    std::uint64_t x = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
    if (s.empty() || s[0] == '-' || s[0] == '+' || ec != std::errc() || end != s.data() + s.size())
      fail(v, what + ": expected an unsigned integer, got " + describe(v));
    return x;
  }

  bool boolean(const YAML::Node& v, const std::string& what) const {
    if (!v.IsScalar() || (v.Scalar() != "true" && v.Scalar() != "false"))
      fail(v, what + ": expected true or false, got " + describe(v));
    return v.Scalar() == "true";
  }

  std::string string(const YAML::Node& v, const std::string& what) const {
    if (!v.IsScalar() || v.Scalar().empty())
      fail(v, what + ": expected a non-empty string, got " + describe(v));
    return v.Scalar();
  }

  void vec3(const YAML::Node& v, const std::string& what, std::vector<double>& out) const {
    if (!v.IsSequence() || v.size() != 3)
      fail(v, what + ": expected a point [x, y, z], got " + describe(v));
    for (std::size_t i = 0; i < 3; ++i) out.push_back(number(v[i], what + "[" + std::to_string(i) + "]"));
  }

  SizingZone zone(const YAML::Node& z, const std::string& where) const {
    if (!z.IsMap()) fail(z, where + ": expected a mapping {type: ..., size: ...}, got " + describe(z));
    const YAML::Node type_node = z["type"];
    if (!type_node) fail(z, where + ": missing required key 'type' (one of " + join(kZoneTypes) + ")");
    const std::string type = type_node.IsScalar() ? type_node.Scalar() : std::string();
    if (std::find(kZoneTypes.begin(), kZoneTypes.end(), type) == kZoneTypes.end()) {
      const std::string near = closest_match(type, kZoneTypes);
      fail(type_node, where + ": key 'type': unknown zone type " + describe(type_node) +
                          (near.empty() ? "" : " (did you mean '" + near + "'?)") + "; valid types: " +
                          join(kZoneTypes));
    }
    const std::string at = where + " (" + type + ")";
    std::vector<std::string> keys = {"type", "size", "name"};
    for (const std::string& k : zone_keys(type)) keys.push_back(k);
    const auto e = entries(z, keys, at);
    SizingZone out;
    out.kind = SizingZone::Kind(std::find(kZoneTypes.begin(), kZoneTypes.end(), type) - kZoneTypes.begin());
    if (!e.count("size")) fail(z, at + ": missing required key 'size'");
    out.size = positive(e.at("size").value, at + ": key 'size'");
    if (e.count("name")) out.name = string(e.at("name").value, at + ": key 'name'");
    for (const std::string& k : zone_keys(type))
      if (!e.count(k) && k != "angle") fail(z, at + ": missing required key '" + k + "'");
    auto key = [&](const std::string& k) { return at + ": key '" + k + "'"; };
    switch (out.kind) {
      case SizingZone::Kind::sharp_edges:
        if (e.count("angle")) {
          out.angle_deg = number(e.at("angle").value, key("angle"));
          if (!(out.angle_deg > 0 && out.angle_deg < 180))
            fail(e.at("angle").value, key("angle") + ": must be in (0, 180) degrees");
        }
        break;
      case SizingZone::Kind::polyline: {
        const YAML::Node p = e.at("points").value;
        if (!p.IsSequence() || p.size() < 2)
          fail(p, key("points") + ": expected a list of at least 2 points [x, y, z], got " + describe(p));
        for (std::size_t i = 0; i < p.size(); ++i) {
          vec3(p[i], key("points") + "[" + std::to_string(i) + "]", out.coords);
          if (i > 0 && std::equal(out.coords.end() - 3, out.coords.end(), out.coords.end() - 6))
            fail(p[i], key("points") + "[" + std::to_string(i) + "]: repeats the previous point");
        }
        break;
      }
      case SizingZone::Kind::segment:
        vec3(e.at("from").value, key("from"), out.coords);
        vec3(e.at("to").value, key("to"), out.coords);
        if (std::equal(out.coords.begin(), out.coords.begin() + 3, out.coords.begin() + 3))
          fail(e.at("to").value, key("to") + ": equals 'from' (a segment needs two distinct ends)");
        break;
      case SizingZone::Kind::plane:
        vec3(e.at("origin").value, key("origin"), out.coords);
        vec3(e.at("normal").value, key("normal"), out.coords);
        if (out.coords[3] == 0 && out.coords[4] == 0 && out.coords[5] == 0)
          fail(e.at("normal").value, key("normal") + ": must not be the zero vector");
        break;
      case SizingZone::Kind::point:
        vec3(e.at("at").value, key("at"), out.coords);
        break;
      case SizingZone::Kind::box:
        vec3(e.at("min").value, key("min"), out.coords);
        vec3(e.at("max").value, key("max"), out.coords);
        for (int i = 0; i < 3; ++i)
          if (out.coords[i] > out.coords[3 + i])
            fail(e.at("max").value, key("max") + ": is below 'min' in coordinate " + "xyz"[i]);
        break;
      case SizingZone::Kind::ball:
        vec3(e.at("center").value, key("center"), out.coords);
        out.coords.push_back(positive(e.at("radius").value, key("radius")));
        break;
    }
    return out;
  }

  /// An output path: relative to the output directory, and inside it unless allowed.
  std::string resolve_output(const YAML::Node& v, const std::string& what) const {
    const fs::path p = string(v, what);
    const fs::path full = (p.is_absolute() || out_.empty() ? p : out_ / p).lexically_normal();
    if (allow_outside_) return full.string();
    const std::string dir = out_.empty() ? std::string(".") : out_.string();
    const std::string allow = " (outputs stay inside the output directory '" + dir +
                              "', --out-dir; --allow-outside-out-dir permits this)";
    if (p.is_absolute()) fail(v, what + ": '" + p.string() + "' is an absolute path" + allow);
    const fs::path rel = p.lexically_normal();
    if (rel.empty() || *rel.begin() == ".." || rel.filename().empty() || rel == ".")
      fail(v, what + ": '" + p.string() + "' leads outside the output directory" + allow);
    // A symbolic link inside the directory may still lead out. Both made absolute first: the
    // weakly canonical form of a relative path that does not exist yet stays relative, so
    // `kdmesh batch jobs.yaml` run in the YAML's own folder refused every new output.
    std::error_code e1, e2, e3, e4;
    const fs::path adir = fs::absolute(dir, e3), afull = fs::absolute(full, e4);
    const fs::path cdir = fs::weakly_canonical(adir, e1), cfull = fs::weakly_canonical(afull, e2);
    if (!e1 && !e2 && !e3 && !e4) {
      const fs::path r = cfull.lexically_relative(cdir);
      if (r.empty() || *r.begin() == "..")
        fail(v, what + ": '" + p.string() + "' leads outside the output directory through a symbolic link" +
                    allow);
    }
    return full.string();
  }

  /// One entry of `groups`: {name, dim?, exactly one of zone / point / box {min, max}}.
  GroupSpec group(const YAML::Node& node, const std::string& where) const {
    const auto e = entries(node, kGroupKeys, where);
    GroupSpec g;
    g.origin = file_ + ":" + std::to_string(line_of(node));
    if (!e.count("name")) fail(node, where + ": missing required key 'name'");
    g.name = string(e.at("name").value, where + ": key 'name'");
    const std::string w = where + " (" + g.name + ")";
    if (e.count("dim")) {
      const YAML::Node v = e.at("dim").value;
      const std::uint64_t d = unsigned_integer(v, w + ": key 'dim'");
      if (d != 1 && d != 2) fail(v, w + ": key 'dim': must be 1 (curves) or 2 (surface patches)");
      g.dim = int(d);
    }
    const int ways = int(e.count("zone")) + int(e.count("point")) + int(e.count("box"));
    if (ways != 1) fail(node, w + ": give exactly one of 'zone', 'point' or 'box'");
    if (e.count("zone")) {
      g.by = GroupSpec::Select::zone;
      g.zone = string(e.at("zone").value, w + ": key 'zone'");
    } else if (e.count("point")) {
      g.by = GroupSpec::Select::point;
      std::vector<double> p;
      vec3(e.at("point").value, w + ": key 'point'", p);
      std::copy(p.begin(), p.end(), g.point);
      if (g.dim == 0) g.dim = 2;
    } else {
      g.by = GroupSpec::Select::box;
      const auto b = entries(e.at("box").value, {"min", "max"}, w + ": key 'box'");
      if (!b.count("min") || !b.count("max")) fail(e.at("box").value, w + ": key 'box': needs 'min' and 'max'");
      std::vector<double> lo, hi;
      vec3(b.at("min").value, w + ": key 'box': key 'min'", lo);
      vec3(b.at("max").value, w + ": key 'box': key 'max'", hi);
      std::copy(lo.begin(), lo.end(), g.box_min);
      std::copy(hi.begin(), hi.end(), g.box_max);
      if (g.dim == 0) g.dim = 2;
    }
    return g;
  }

  /// A surface file: relative to the batch file's directory; must exist, with an extension
  /// read_surface reads.
  std::string surface_path(const YAML::Node& v, const std::string& what) const {
    const fs::path given = string(v, what);
    const fs::path p = (given.is_absolute() ? given : base_ / given).lexically_normal();
    if (!is_surface_extension(p.extension().string()))
      fail(v, what + ": '" + given.string() + "' is not an .stl, .ply, .obj or .off file");
    std::error_code ec;
    if (!fs::is_regular_file(p, ec))
      fail(v, what + ": file '" + p.string() + "' not found" +
                  (given.is_absolute() ? "" : " (relative paths are resolved against the batch file's directory)"));
    return p.string();
  }

  /// `bodies`: a non-empty list of {name, input}, names [A-Za-z0-9_-]+ and distinct.
  std::vector<BodyInput> bodies(const YAML::Node& list, const std::string& what) const {
    if (!list.IsSequence() || list.size() == 0)
      fail(list, what + ": expected a non-empty list of {name, input}, got " + describe(list));
    std::vector<BodyInput> out;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string w = what + "[" + std::to_string(i) + "]";
      const std::map<std::string, Entry> b = entries(list[i], kBodyKeys, w);
      for (const char* req : {"name", "input"})
        if (!b.count(req)) fail(list[i], w + ": missing required key '" + std::string(req) + "'");
      BodyInput body;
      body.name = string(b.at("name").value, w + ": key 'name'");
      if (body.name.empty() || !std::all_of(body.name.begin(), body.name.end(), [](char c) {
            return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
          }))
        fail(b.at("name").value, w + ": key 'name': '" + body.name +
                                     "' must be letters, digits, '_' and '-' (it names a region in the solver formats)");
      for (const BodyInput& o : out)
        if (o.name == body.name) fail(b.at("name").value, w + ": key 'name': body '" + body.name + "' is listed twice");
      body.input = surface_path(b.at("input").value, w + ": key 'input'");
      out.push_back(std::move(body));
    }
    return out;
  }

  /// Options of one job given in memory (parse_job): `name` may be absent ("mesh"), and so may
  /// `input` (the surface comes with them).
  void set_in_memory() { in_memory_ = true; }

  MeshJob job(const YAML::Node& node, const std::map<std::string, Entry>& defaults,
              std::size_t index) const {
    const std::string where0 = in_memory_ ? std::string("options") : "jobs[" + std::to_string(index) + "]";
    std::map<std::string, Entry> e = entries(node, kJobKeys, where0);
    for (const auto& [k, d] : defaults) e.emplace(k, d);  // job keys win
    MeshJob job;
    job.origin = file_ + ":" + std::to_string(line_of(node));
    if (!e.count("name") && !in_memory_) fail(node, where0 + ": missing required key 'name'");
    job.name = e.count("name") ? string(e.at("name").value, where0 + ": key 'name'") : std::string("mesh");
    if (!std::all_of(job.name.begin(), job.name.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '.' || c == '-';
        }))
      fail(e.at("name").value, where0 + ": key 'name': '" + job.name +
                                   "' may only contain letters, digits, '_', '.' and '-'");
    const std::string where = "job '" + job.name + "'";
    auto key = [&](const std::string& k) { return where + ": key '" + k + "'"; };
    for (const char* req : {"input", "size"})
      if (!e.count(req) && !(std::string(req) == "input" && (in_memory_ || e.count("bodies"))))
        fail(node, where + ": missing required key '" + std::string(req) + "'");

    if (e.count("input") && e.count("bodies"))
      fail(e.at("bodies").key, key("bodies") + ": give either 'input' (one surface) or 'bodies', not both");
    if (e.count("input")) {
      job.input = surface_path(e.at("input").value, key("input"));
    } else if (e.count("bodies")) {
      job.bodies = bodies(e.at("bodies").value, key("bodies"));
      job.input.clear();
      for (const BodyInput& b : job.bodies) job.input += (job.input.empty() ? "" : " + ") + b.input;
    } else {
      job.input.clear();  // given in memory: the caller names it
    }
    if (e.count("scale")) job.scale = positive(e.at("scale").value, key("scale"));
    job.sizing.max_size = positive(e.at("size").value, key("size"));
    job.sizing.min_size = job.sizing.max_size / 1000;
    if (e.count("min_size")) {
      job.sizing.min_size = positive(e.at("min_size").value, key("min_size"));
      if (job.sizing.min_size > job.sizing.max_size)
        fail(e.at("min_size").value, key("min_size") + ": must not exceed 'size'");
    }
    if (e.count("gradation")) job.sizing.gradation = positive(e.at("gradation").value, key("gradation"));
    sizing_keys(e, job);
    run_keys(e, job);
    output_keys(e, job);
    return job;
  }

  /// A job's keys of the surface, the sizing field and the checks' tolerances (job()).
  void sizing_keys(const std::map<std::string, Entry>& e, MeshJob& job) const {
    const std::string where = "job '" + job.name + "'";
    auto key = [&](const std::string& k) { return where + ": key '" + k + "'"; };
    if (e.count("sharp_angle")) {
      const YAML::Node v = e.at("sharp_angle").value;
      job.sharp_angle = number(v, key("sharp_angle"));
      if (!(job.sharp_angle >= 0 && job.sharp_angle < 180))
        fail(v, key("sharp_angle") + ": must be in [0, 180) degrees, got " + v.Scalar());
    }
    if (e.count("curvature_angle")) {
      const YAML::Node v = e.at("curvature_angle").value;
      job.curvature_angle = number(v, key("curvature_angle"));
      if (!(job.curvature_angle >= 0 && job.curvature_angle <= 90))
        fail(v, key("curvature_angle") + ": must be in [0, 90] degrees, got " + v.Scalar());
    }
    if (e.count("chordal_deviation")) {
      const YAML::Node v = e.at("chordal_deviation").value;
      if (v.IsScalar() && v.Scalar() == "auto") {
        job.chordal_deviation = -1;
      } else {
        job.chordal_deviation = number(v, key("chordal_deviation"));
        if (!(job.chordal_deviation >= 0) || !std::isfinite(job.chordal_deviation))
          fail(v, key("chordal_deviation") + ": must be 'auto' or a finite number >= 0, got " + v.Scalar());
      }
    }
    if (e.count("thickness_layers")) {
      const YAML::Node v = e.at("thickness_layers").value;
      job.thickness_layers = number(v, key("thickness_layers"));
      if (!(job.thickness_layers >= 0 && job.thickness_layers <= 16))
        fail(v, key("thickness_layers") + ": must be in [0, 16], got " + v.Scalar());
    }
    if (e.count("auto_creases")) job.auto_creases = boolean(e.at("auto_creases").value, key("auto_creases"));
    if (e.count("tolerance")) {
      const YAML::Node t = e.at("tolerance").value;
      if (!t.IsMap()) fail(t, key("tolerance") + ": expected a map {hausdorff: H, volume: V}, got " + describe(t));
      for (const auto& kv : t) {
        const std::string k = kv.first.as<std::string>();
        const double x = number(kv.second, key("tolerance") + "." + k);
        if (k == "hausdorff") {
          if (!(x > 0 && x <= 1)) fail(kv.second, key("tolerance.hausdorff") + ": must be in (0, 1], got " + kv.second.Scalar());
          job.check.hausdorff_tolerance = x;
        } else if (k == "volume") {
          if (!(x > 0 && x <= 1)) fail(kv.second, key("tolerance.volume") + ": must be in (0, 1], got " + kv.second.Scalar());
          job.check.volume_tolerance = x;
        } else {
          fail(kv.first, key("tolerance") + ": unknown key '" + k + "' (valid: hausdorff, volume)");
        }
      }
    }
    if (e.count("max_refinements")) {
      const YAML::Node v = e.at("max_refinements").value;
      const std::uint64_t n = unsigned_integer(v, key("max_refinements"));
      if (n > 64) fail(v, key("max_refinements") + ": must be in [0, 64], got " + v.Scalar());
      job.max_refinements = int(n);
    }
    if (e.count("zones")) {
      const YAML::Node z = e.at("zones").value;
      if (!z.IsSequence()) fail(z, key("zones") + ": expected a list, got " + describe(z));
      if (zone_limit_ > 0 && double(z.size()) > zone_limit_)
        fail(z, key("zones") + ": " + std::to_string(z.size()) + " zones need more than the memory limit (at most " +
                    std::to_string(std::uint64_t(zone_limit_)) + " zones; --max-memory)");
      for (std::size_t i = 0; i < z.size(); ++i)
        job.sizing.zones.push_back(zone(z[i], where + ": zones[" + std::to_string(i) + "]"));
    }
  }

  /// A job's keys of the run: order, seed, checks, groups, limits, repairs (job()).
  void run_keys(const std::map<std::string, Entry>& e, MeshJob& job) const {
    const std::string where = "job '" + job.name + "'";
    auto key = [&](const std::string& k) { return where + ": key '" + k + "'"; };
    if (e.count("order")) {
      const YAML::Node v = e.at("order").value;
      const std::string name = string(v, key("order"));
      try {
        job.order.kind = parse_order_kind(name);
      } catch (const UsageError&) {
        const std::string near = closest_match(name, order_kind_names());
        fail(v, key("order") + ": unknown order '" + name + "'" +
                    (near.empty() ? "" : " (did you mean '" + near + "'?)") +
                    "; valid orders: " + join(order_kind_names()));
      }
    }
    if (e.count("seed")) job.seed = unsigned_integer(e.at("seed").value, key("seed"));
    job.order.seed = job.seed;
    if (e.count("check")) {
      const YAML::Node c = e.at("check").value;
      if (!c.IsSequence()) fail(c, key("check") + ": expected a list of " + join(kChecks) + ", got " + describe(c));
      for (std::size_t i = 0; i < c.size(); ++i) {
        const std::string name = c[i].IsScalar() ? c[i].Scalar() : std::string();
        if (name == "tetgen" && !tetgen_available()) fail(c[i], key("check") + ": " + without_tetgen_message("tetgen"));
        if (name == "tetgen") job.check_tetgen = true;
        else if (name == "delaunay") job.check_delaunay = true;
        else {
          const std::string near = closest_match(name, kChecks);
          fail(c[i], key("check") + ": unknown check " + describe(c[i]) +
                         (near.empty() ? "" : " (did you mean '" + near + "'?)") + "; valid checks: " + join(kChecks));
        }
      }
    }
    if (e.count("groups")) {
      const YAML::Node g = e.at("groups").value;
      if (!g.IsSequence()) fail(g, key("groups") + ": expected a list, got " + describe(g));
      for (std::size_t i = 0; i < g.size(); ++i) job.groups.push_back(group(g[i], where + ": groups[" + std::to_string(i) + "]"));
    }
    if (e.count("patch_groups"))
      job.group_options.patch_groups = job.group_options.curve_groups =
          boolean(e.at("patch_groups").value, key("patch_groups"));
    if (e.count("timeout")) job.timeout = positive(e.at("timeout").value, key("timeout"));
    if (e.count("improve")) job.improve = boolean(e.at("improve").value, key("improve"));
    if (e.count("element_order")) {
      const YAML::Node v = e.at("element_order").value;
      const std::uint64_t n = unsigned_integer(v, key("element_order"));
      if (n != 1 && n != 2) fail(v, key("element_order") + ": must be 1 or 2");
      job.element_order = int(n);
    }
    if (e.count("msh_version")) {
      const YAML::Node v = e.at("msh_version").value;
      const std::string text = v.IsScalar() ? v.Scalar() : std::string();
      if (text != "4.1" && text != "2.2") fail(v, key("msh_version") + ": must be 4.1 or 2.2, got " + describe(v));
      job.msh_version = text == "4.1" ? 41 : 22;
    }
    if (e.count("repair")) {
      const YAML::Node c = e.at("repair").value;
      if (!c.IsSequence())
        fail(c, key("repair") + ": expected a list of degenerate, duplicates, orientation, got " + describe(c));
      job.repair = {};
      for (std::size_t i = 0; i < c.size(); ++i) {
        const std::string name = c[i].IsScalar() ? c[i].Scalar() : std::string();
        try {
          const SurfaceRepairOptions one = parse_surface_repairs(name, key("repair"));
          job.repair.degenerate |= one.degenerate;
          job.repair.duplicates |= one.duplicates;
          job.repair.orientation |= one.orientation;
        } catch (const UsageError& err) {
          fail(c[i], err.what());
        }
      }
    }
    if (e.count("max_memory")) {
      const YAML::Node v = e.at("max_memory").value;
      const std::string text = string(v, key("max_memory"));
      try {
        job.max_memory = parse_memory_amount(text, key("max_memory"));
      } catch (const UsageError& err) {
        fail(v, err.what());
      }
    }
  }

  /// A job's output files (job()).
  void output_keys(const std::map<std::string, Entry>& e, MeshJob& job) const {
    const std::string where = "job '" + job.name + "'";
    auto key = [&](const std::string& k) { return where + ": key '" + k + "'"; };
    if (e.count("output")) {
      const auto o = entries(e.at("output").value, kOutputKeys, key("output"));
      const std::string k = key("output");
      if (o.count("vtu")) job.vtu = resolve_output(o.at("vtu").value, k + ": key 'vtu'");
      if (o.count("summary")) job.summary = resolve_output(o.at("summary").value, k + ": key 'summary'");
      if (o.count("nodes")) job.nodes = resolve_output(o.at("nodes").value, k + ": key 'nodes'");
      if (o.count("msh")) job.msh = resolve_output(o.at("msh").value, k + ": key 'msh'");
      if (o.count("inp")) job.inp = resolve_output(o.at("inp").value, k + ": key 'inp'");
      if (o.count("mesh")) job.medit = resolve_output(o.at("mesh").value, k + ": key 'mesh'");
      if (o.count("boundary_vtu"))
        job.boundary_vtu = resolve_output(o.at("boundary_vtu").value, k + ": key 'boundary_vtu'");
      if (o.count("xdmf")) job.xdmf = resolve_output(o.at("xdmf").value, k + ": key 'xdmf'");
      if (o.count("exodus")) job.exodus = resolve_output(o.at("exodus").value, k + ": key 'exodus'");
    }
  }

  BatchConfig load(const YAML::Node& root) const {
    if (!root.IsDefined() || root.IsNull())
      throw_input(file_, 0, "empty batch file: expected a mapping with a 'jobs' list");
    const auto top = entries(root, kTopKeys, "batch file");
    std::map<std::string, Entry> defaults;
    if (top.count("defaults")) defaults = entries(top.at("defaults").value, kJobKeys, "defaults");
    if (!top.count("jobs")) fail(root, "batch file: missing required key 'jobs'");
    const YAML::Node jobs = top.at("jobs").value;
    if (!jobs.IsSequence() || jobs.size() == 0)
      fail(jobs.IsNull() ? top.at("jobs").key : jobs,
           "key 'jobs': expected a non-empty list of jobs, got " + describe(jobs));
    BatchConfig config;
    config.file = file_;
    std::map<std::string, std::pair<std::string, std::string>> writers;  // output path -> job, key
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      MeshJob j = job(jobs[i], defaults, i);
      for (const MeshJob& other : config.jobs)
        if (other.name == j.name)
          fail(jobs[i]["name"] ? jobs[i]["name"] : jobs[i],
               "job '" + j.name + "': key 'name': duplicate job name (first defined at " + other.origin + ")");
      for (const JobOutput& out : job_outputs(j)) {
        const char* const k = out.key;
        const std::string* const path = &out.path;
        std::error_code ec;
        fs::path canon_path = fs::weakly_canonical(*path, ec);
        if (ec) canon_path = fs::absolute(*path, ec).lexically_normal();
        const std::string canon = canon_path.string();
        const auto it = writers.find(canon);
        if (it != writers.end())
          fail(jobs[i]["output"] ? jobs[i]["output"]
               : defaults.count("output") ? defaults.at("output").value
                                          : jobs[i],
               "job '" + j.name + "': key 'output': '" + *path + "' (" + k + ") is also written by " +
                   (it->second.first == j.name ? "this job" : "job '" + it->second.first + "'") + " (" +
                   it->second.second + ")");
        writers[canon] = {j.name, k};
      }
      config.jobs.push_back(std::move(j));
    }
    check_batch_paths(config, jobs);
    return config;
  }

  /// Every input and output of the batch as one run: no output is any job's input, and no two
  /// outputs are one file, compared by device and inode (hard links, symbolic links, "a/../b").
  void check_batch_paths(const BatchConfig& config, const YAML::Node& jobs) const {
    std::vector<PathUse> uses;
    std::vector<std::size_t> owner;
    for (std::size_t i = 0; i < config.jobs.size(); ++i)
      for (PathUse& u : job_path_uses(config.jobs[i])) {
        u.label = "job '" + config.jobs[i].name + "' " + u.label;
        uses.push_back(std::move(u));
        owner.push_back(i);
      }
    const auto clash = find_path_clash(uses);
    if (!clash) return;
    const YAML::Node at = jobs[owner[clash->second]];
    const PathUse& later = uses[clash->second];
    const YAML::Node in = at["input"] ? at["input"] : at["bodies"];
    fail(at["output"] && later.output ? at["output"] : in && !later.output ? in : at,
         describe_path_clash(uses, *clash) +
             (uses[clash->first].output == later.output ? "" : " (the result would depend on the order of the jobs)"));
  }

 private:
  std::string file_;
  fs::path base_, out_;
  bool allow_outside_ = false;
  double zone_limit_ = 0;  ///< most zones a job may have (0: no limit)
  bool in_memory_ = false;
};

}  // namespace

/// Counts what a document holds besides nulls, and where its first such event is.
class DocumentProbe : public YAML::EventHandler {
 public:
  std::uint64_t first_line = 0;  ///< 1-based line of the first non-null event (0: none)
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { seen(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t, const std::string&) override { seen(m); }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    seen(m);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    seen(m);
  }
  void OnMapEnd() override {}

 private:
  void seen(const YAML::Mark& m) {
    if (!first_line) first_line = m.line >= 0 ? std::uint64_t(m.line) + 1 : 1;
  }
};

/// The line of the first non-null document after the first one (0: none). Not YAML::LoadAll:
/// yaml-cpp 0.7 (Debian 12) loops forever in it on some broken input, each round adding an
/// empty document (fuzz_config found two; fixed upstream in yaml-cpp PR 1319). A stream has at
/// most one document per line, so the documents are probed up to that count.
std::uint64_t second_document_line(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  const std::size_t max_documents = std::size_t(std::count(text.begin(), text.end(), '\n')) + 2;
  try {
    for (std::size_t d = 0; d < max_documents; ++d) {
      DocumentProbe probe;
      if (!parser.HandleNextDocument(probe)) return 0;
      if (d > 0 && probe.first_line) return probe.first_line;
    }
  } catch (const YAML::Exception& e) {  // an error after the first document: its line
    return e.mark.line >= 0 ? std::uint64_t(e.mark.line) + 1 : 1;
  }
  return 0;
}

BatchConfig load_batch_config(const std::string& path, const BatchLoadOptions& options) {
  const double limit = effective_memory_limit(options.max_memory);
  std::string text;
  try {
    const double max_bytes = limit > 0 ? limit / kConfigBytesPerByte : 0;
    text = read_whole_file(path, max_bytes > 0 ? std::uint64_t(std::max(1.0, max_bytes)) : 0);
  } catch (const InputError& e) {
    const std::string why = std::string(e.what()).substr(path.size() + 2);
    throw_input(path, 0, why + (limit > 0 && why.find("too large") != std::string::npos
                                    ? " (parsing a batch file takes up to " + std::to_string(int(kConfigBytesPerByte)) +
                                          " bytes of memory per byte; --max-memory)"
                                    : std::string()));
  }
  auto syntax_error = [&](const YAML::Exception& e) {
    throw_input(path, e.mark.line >= 0 ? std::uint64_t(e.mark.line) + 1 : 0,
                "YAML syntax error" +
                    (e.mark.column >= 0 ? " at column " + std::to_string(e.mark.column + 1) : std::string()) +
                    ": " + e.msg);
  };
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    syntax_error(e);
  }
  if (const std::uint64_t line = second_document_line(text))
    throw_input(path, line,
                "a second YAML document (after '---'): a batch file is one document; put every job in its "
                "'jobs' list");
  const fs::path base = fs::path(path).parent_path();
  const fs::path out = options.out_dir.empty() ? base : fs::path(options.out_dir);
  try {
    return Loader(path, base, out, options.allow_outside_out_dir, limit > 0 ? limit / kBytesPerZone : 0).load(root);
  } catch (const YAML::Exception& e) {  // not expected: every access is checked first
    throw_input(path, e.mark.line >= 0 ? std::uint64_t(e.mark.line) + 1 : 0, e.msg);
  }
}

MeshJob parse_job(const std::string& text, const std::string& label) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw_input(label, e.mark.line >= 0 ? std::uint64_t(e.mark.line) + 1 : 0, "syntax error: " + e.msg);
  }
  if (!root.IsMap()) throw_input(label, 0, "options: expected a mapping of job keys");
  const fs::path here = fs::current_path();
  Loader loader(label, here, here, /*allow_outside=*/true, /*zone_limit=*/0);
  loader.set_in_memory();
  try {
    return loader.job(root, {}, 0);
  } catch (const YAML::Exception& e) {  // not expected: every access is checked first
    throw_input(label, e.mark.line >= 0 ? std::uint64_t(e.mark.line) + 1 : 0, e.msg);
  }
}

BatchConfig load_batch_config(const std::string& path, const std::string& out_dir) {
  BatchLoadOptions o;
  o.out_dir = out_dir;
  return load_batch_config(path, o);
}

}  // namespace kdmesh
