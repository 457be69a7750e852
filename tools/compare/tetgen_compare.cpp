// kdmesh — kdmesh against TetGen 1.5 (-pq) on the same surface at a matching size.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Why TetGen runs in a forked child through its library, not the Debian `tetgen` program on
// files: TetGen 1.5's error exit frees its memory and throws, after which its destructor frees
// it again, so the process that called it crashes (mesher/reference/tetgen_delaunay.cpp). A child
// process contains that, like the program would, but without writing and parsing .poly /
// .b.node / .b.ele / .b.mtr / .node / .ele files: the time measured is tetrahedralize()'s own
// (no file I/O on either side), the same libtet that --check uses is compared, and the PLC
// and the background mesh are handed over exactly (doubles, not decimal text). The child
// sends its mesh back through a pipe; its stdout and stderr (TetGen's log, and glibc's
// message if it crashes) go through a second pipe, from which TetGen's own stage times are
// read.
#include "tools/compare/tetgen_compare.h"

#include <malloc.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <new>
#include <sstream>
#include <unordered_set>

#ifdef KDMESH_WITH_TETGEN  // else run_tetgen refuses before the child would call TetGen
#ifndef TETLIBRARY
#define TETLIBRARY  // as libtet was built (its terminatetetgen throws instead of exiting)
#endif
#include <tetgen.h>
#endif

#include "core/fe_mesh.h"
#include "core/timer.h"
#include "io/medit_reader.h"
#include "io/surface_io.h"
#include "io/vtu_writer.h"
#include "mesher/delaunay/delaunay.h"
#include "mesher/order/order.h"
#include "mesher/delaunay/predicates.h"
#include "mesher/tet_quality.h"
#include "mesher/reference/reference_delaunay.h"
#include "mesher/quality/size_fidelity.h"
#include "mesher/surface/surface_query.h"
#include "mesher/surface/surface_repair.h"

namespace kdmesh {

// ---- switches ------------------------------------------------------------------------------

const char* tetgen_sizing_name(TetgenSizing s) {
  switch (s) {
    case TetgenSizing::mtr: return "mtr";
    case TetgenSizing::volume: return "volume";
    case TetgenSizing::none: return "none";
  }
  return "none";
}

TetgenSizing parse_tetgen_sizing(const std::string& name) {
  for (TetgenSizing s : {TetgenSizing::mtr, TetgenSizing::volume, TetgenSizing::none})
    if (name == tetgen_sizing_name(s)) return s;
  throw UsageError("--tetgen-sizing " + name + ": expected mtr, volume or none");
}

namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

/// Skips a numeric parameter the way TetGen 1.5's parse_commandline reads it: digits and '.',
/// and with `exponent` also 'e', '-', '+'. Returns the index of its last character (or j).
std::size_t skip_number(const std::string& s, std::size_t j, bool exponent) {
  if (j + 1 >= s.size() || !(is_digit(s[j + 1]) || s[j + 1] == '.')) return j;
  while (j + 1 < s.size() &&
         (is_digit(s[j + 1]) || s[j + 1] == '.' ||
          (exponent && (s[j + 1] == 'e' || s[j + 1] == '-' || s[j + 1] == '+'))))
    ++j;
  return j;
}

}  // namespace

std::string tetgen_switch_string(const std::string& user, TetgenSizing sizing, double max_size) {
  std::string s = user;
  if (!s.empty() && s[0] == '-') s.erase(0, 1);
  auto bad = [&](const std::string& why) {
    return UsageError("--tetgen-switches " + user + ": " + why);
  };
  bool plc = false, zero = false;
  for (std::size_t j = 0; j < s.size(); ++j) {
    const char c = s[j];
    switch (c) {
      case 'p': plc = true; j = skip_number(s, j, false); break;
      case 'q':  // q[ratio][/mindihedral][/maxdihedral]
        j = skip_number(s, j, false);
        for (int k = 0; k < 2 && j + 1 < s.size() && (s[j + 1] == '/' || s[j + 1] == ','); ++k)
          j = skip_number(s, j + 1, false);
        break;
      case 'a':
        if (j + 1 < s.size() && (is_digit(s[j + 1]) || s[j + 1] == '.')) {
          if (sizing != TetgenSizing::none)
            throw bad("a volume bound conflicts with --tetgen-sizing " + std::string(tetgen_sizing_name(sizing)) +
                      " (use --tetgen-sizing none to give your own -a)");
          j = skip_number(s, j, true);
        }
        break;
      case 'S': case 'T': j = skip_number(s, j, true); break;
      case 'Y': if (j + 1 < s.size() && is_digit(s[j + 1])) ++j; break;
      case 'D': if (j + 1 < s.size() && s[j + 1] >= '1' && s[j + 1] <= '3') ++j; break;
      case 'X': if (j + 1 < s.size() && s[j + 1] == '1') ++j; break;
      case 'b': if (j + 1 < s.size() && s[j + 1] == '0') ++j; break;
      case 'O':
        if (j + 1 < s.size() && is_digit(s[j + 1])) ++j;
        if (j + 1 < s.size() && (s[j + 1] == '/' || s[j + 1] == ',')) {
          ++j;
          if (j + 1 < s.size() && s[j + 1] >= '0' && s[j + 1] <= '7') ++j;
        }
        break;
      case 'o':
        if (j + 1 < s.size() && s[j + 1] == '2') throw bad("o2 (quadratic tets) is not compared");
        if (j + 1 < s.size() && (s[j + 1] == '/' || s[j + 1] == ',')) j = skip_number(s, j + 1, false);
        break;
      case 'z': zero = true; break;
      case 'A': case 'M': case 'f': case 'e': case 'n': case 'J': case 'B': case 'F':
      case 'Q': case 'V': case 'l': case 'L': case 'R': case 'C':
        break;
      case 'm': throw bad("m is added by --tetgen-sizing mtr (with kdmesh's background mesh)");
      case 'r': throw bad("r refines an existing mesh; the comparison meshes the surface (p)");
      case 'i': throw bad("i inserts extra points, which the comparison does not provide");
      case 'w': throw bad("w (weighted Delaunay) needs point weights");
      case 's': throw bad("s (piecewise smooth complex) is not a surface input");
      case 'c': throw bad("c keeps the convex hull: the mesh would not be the solid's");
      case 'd': throw bad("d only detects self-intersections, it makes no mesh");
      case 'N': case 'E': case 'I': throw bad(std::string(1, c) + " suppresses the nodes or tets compared");
      case 'g': case 'k': case 'v': throw bad(std::string(1, c) + " writes extra files");
      default:
        throw bad(std::string("unknown or unsupported switch '") + c + "' (TetGen 1.5 switches, e.g. pq1.414/12)");
    }
  }
  if (!plc) throw bad("needs p (the input is a surface, a PLC)");
  std::string out = s;
  if (!zero) out += 'z';
  if (sizing == TetgenSizing::mtr) out += 'm';
  if (sizing == TetgenSizing::volume) {
    if (!(max_size > 0)) throw UsageError("--tetgen-sizing volume needs a size > 0");
    char buf[64];
    std::snprintf(buf, sizeof buf, "a%.17g", max_size * max_size * max_size / (6 * std::sqrt(2.0)));
    out += buf;
  }
  return out;
}

// ---- background mesh and holes -------------------------------------------------------------

namespace {

/// A cell of the thinning grid of one level.
struct ThinCell {
  int level;
  std::int64_t c[3];
  bool operator==(const ThinCell& o) const {
    return level == o.level && c[0] == o.c[0] && c[1] == o.c[1] && c[2] == o.c[2];
  }
};

struct ThinCellHash {
  std::size_t operator()(const ThinCell& k) const {
    std::uint64_t h = std::uint64_t(k.level + 1100) * 0x9E3779B97F4A7C15ull;
    for (std::int64_t c : k.c) h = (h ^ std::uint64_t(c)) * 0xBF58476D1CE4E5B9ull;
    return std::size_t(h ^ (h >> 31));
  }
};

}  // namespace

PointSet thin_nodes(const PointSet& nodes, const SizingField& sizing, double spacing) {
  if (!(spacing > 0)) return nodes;
  std::unordered_set<ThinCell, ThinCellHash> taken;
  PointSet kept;
  for (std::uint32_t i = 0; i < nodes.size(); ++i) {
    const double* p = nodes.p(i);
    ThinCell cell{};
    std::frexp(spacing * sizing(p), &cell.level);  // spacing * h = f * 2^e, f in [0.5, 1)
    --cell.level;                                   // 2^level <= spacing * h < 2^(level + 1)
    for (int k = 0; k < 3; ++k) cell.c[k] = std::int64_t(std::floor(std::ldexp(p[k], -cell.level)));
    if (taken.insert(cell).second) kept.push_back(p[0], p[1], p[2]);
  }
  return kept;
}

BackgroundMesh make_background_mesh(const PointSet& nodes, const SurfaceMesh& surface,
                                    const SizingField& sizing, double spacing) {
  PointSet all = thin_nodes(nodes, sizing, spacing);
  all.xyz.insert(all.xyz.end(), surface.points.xyz.begin(), surface.points.xyz.end());
  if (all.size() >= std::size_t(INT32_MAX)) throw UsageError("background mesh: too many points for TetGen (int ids)");
  OrderOptions oo;  // kd-bfs; deterministic
  const DelaunayResult d = delaunay(all, make_order(all, oo));
  const std::vector<std::uint32_t> tets = finite_tets(d.tri);
  // Keep the points some tet uses (exact duplicates are skipped by the kernel), renumbered.
  std::vector<std::uint32_t> id(all.size(), kInfiniteVertex);
  BackgroundMesh bg;
  bg.tets.reserve(tets.size());
  for (std::uint32_t v : tets) {
    if (id[v] == kInfiniteVertex) {
      id[v] = std::uint32_t(bg.points.size());
      const double* p = all.p(v);
      bg.points.push_back(p[0], p[1], p[2]);
      bg.size.push_back(sizing(p));
    }
    bg.tets.push_back(id[v]);
  }
  return bg;
}

PointSet void_hole_points(const PreparedSurface& s, const SurfaceQuery& query) {
  PointSet holes;
  const SurfaceMesh& m = s.mesh;
  for (std::uint32_t shell = 0; shell < s.shell_volume.size(); ++shell) {
    if (!(s.shell_volume[shell] < 0)) continue;  // an outer shell: TetGen removes the outside itself
    // Candidate facets of the void's shell, largest first.
    std::vector<std::pair<double, std::uint32_t>> cand;
    for (std::uint32_t f = 0; f < m.num_tris(); ++f) {
      if (s.tri_shell[f] != shell) continue;
      const std::uint32_t* t = m.tri(f);
      const double *a = m.points.p(t[0]), *b = m.points.p(t[1]), *c = m.points.p(t[2]);
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
      cand.push_back({std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), f});
    }
    std::sort(cand.begin(), cand.end(), [](const auto& x, const auto& y) { return x.first > y.first; });
    bool found = false;
    for (const auto& [twice_area, f] : cand) {
      const std::uint32_t* t = m.tri(f);
      const double *a = m.points.p(t[0]), *b = m.points.p(t[1]), *c = m.points.p(t[2]);
      double longest = 0;
      for (int k = 0; k < 3; ++k) {
        const double *p = m.points.p(t[k]), *q = m.points.p(t[(k + 1) % 3]);
        longest = std::max(longest, std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]));
      }
      if (!(twice_area > 0) || !(longest > 0)) continue;
      const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
      const double n[3] = {(u[1] * v[2] - u[2] * v[1]) / twice_area, (u[2] * v[0] - u[0] * v[2]) / twice_area,
                           (u[0] * v[1] - u[1] * v[0]) / twice_area};
      // The facet's normal points out of the solid, i.e. into the void. Step a tenth of the
      // facet's smallest altitude from its centroid: the centroid projects inside the facet,
      // so the facet is at exactly `d`; if no facet is closer, the segment centroid -> q
      // crosses no surface and q lies in the void this facet bounds.
      const double d = 0.1 * twice_area / longest;
      double q[3];
      for (int k = 0; k < 3; ++k) q[k] = (a[k] + b[k] + c[k]) / 3 + d * n[k];
      if (query.side(q) < 0 && query.distance(q) >= d * (1 - 1e-9)) {
        holes.push_back(q[0], q[1], q[2]);
        found = true;
        break;
      }
    }
    if (!found)
      throw GeometryError("cannot place a hole point for TetGen in the void bounded by shell " + std::to_string(shell));
  }
  return holes;
}

// ---- TetGen in a child process -------------------------------------------------------------

namespace {

constexpr char kMagic[8] = {'K', 'D', 'T', 'G', 'E', 'N', '1', '\n'};

struct ChildHeader {
  char magic[8];
  std::int32_t status;  ///< 0 ok; TetGen's error code (terminatetetgen) otherwise; -1 bad switches
  std::int32_t corners;
  double seconds;
  double added_peak_bytes;
  std::uint64_t points;
  std::uint64_t tets;
};

void write_all(int fd, const void* data, std::size_t n) {
  const char* p = static_cast<const char*>(data);
  for (std::size_t done = 0; done < n;) {
    const ssize_t k = ::write(fd, p + done, n - done);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return;  // the parent is gone
    done += std::size_t(k);
  }
}

/// A "Key:   N kB" line of /proc/self/status, in bytes (0 if unavailable).
double proc_status_bytes(const char* key) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::size_t n = std::strlen(key);
  while (std::getline(f, line))
    if (line.compare(0, n, key) == 0) return 1024.0 * std::strtod(line.c_str() + n, nullptr);
  return 0;
}

/// Copies `n` values into a new[] array (tetgenio frees its arrays with delete[]).
template <class T, class U>
T* new_array(const std::vector<U>& v) {
  T* a = new T[v.size()];
  std::copy(v.begin(), v.end(), a);
  return a;
}

/// The child: builds TetGen's input, runs tetrahedralize, sends the result, exits.
[[noreturn]] void tetgen_child(const PreparedSurface& s, const PointSet& holes, const BackgroundMesh* bg,
                               const std::string& switches, int data_fd, int log_fd) {
  std::signal(SIGINT, SIG_DFL);
  std::signal(SIGTERM, SIG_DFL);
  std::fflush(stdout);
  ::dup2(log_fd, STDOUT_FILENO);
  ::dup2(log_fd, STDERR_FILENO);
  ::close(log_fd);
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // a crash loses at most the current line
  ChildHeader h{};
  std::memcpy(h.magic, kMagic, sizeof kMagic);
  std::vector<double> points;
  std::vector<std::uint32_t> tets;
#ifndef KDMESH_WITH_TETGEN
  (void)s, (void)holes, (void)bg, (void)switches;
  h.status = 2;  // unreachable: run_tetgen refuses first
#else
  try {
    tetgenio in, out, bgm;
    in.firstnumber = 0;
    in.numberofpoints = int(s.mesh.points.size());
    in.pointlist = new_array<REAL>(s.mesh.points.xyz);
    in.numberoffacets = int(s.mesh.num_tris());
    in.facetlist = new tetgenio::facet[s.mesh.num_tris()];
    for (std::size_t f = 0; f < s.mesh.num_tris(); ++f) {
      tetgenio::facet& fa = in.facetlist[f];
      tetgenio::init(&fa);
      fa.numberofpolygons = 1;
      fa.polygonlist = new tetgenio::polygon[1];
      tetgenio::init(&fa.polygonlist[0]);
      fa.polygonlist[0].numberofvertices = 3;
      fa.polygonlist[0].vertexlist = new int[3];
      for (int k = 0; k < 3; ++k) fa.polygonlist[0].vertexlist[k] = int(s.mesh.tri(f)[k]);
    }
    if (!holes.empty()) {
      in.numberofholes = int(holes.size());
      in.holelist = new_array<REAL>(holes.xyz);
    }
    if (bg) {
      bgm.firstnumber = 0;
      bgm.numberofpoints = int(bg->points.size());
      bgm.pointlist = new_array<REAL>(bg->points.xyz);
      bgm.numberofpointmtrs = 1;
      bgm.pointmtrlist = new_array<REAL>(bg->size);
      bgm.numberofcorners = 4;
      bgm.numberoftetrahedra = int(bg->tets.size() / 4);
      bgm.tetrahedronlist = new_array<int>(bg->tets);
    }
    tetgenbehavior b;
    std::vector<char> sw(switches.begin(), switches.end());
    sw.push_back('\0');
    if (!b.parse_commandline(sw.data())) {
      h.status = -1;
    } else {
      // Peak RSS from here on: return the free heap inherited from the parent to the system
      // (else TetGen would reuse those resident pages unseen), reset the high-water mark
      // (Linux >= 4.0), note the baseline.
      ::malloc_trim(0);
      if (FILE* c = std::fopen("/proc/self/clear_refs", "w")) {
        std::fputs("5", c);
        std::fclose(c);
      }
      const double before = proc_status_bytes("VmRSS:");
      Stopwatch clock;
      tetrahedralize(&b, &in, &out, nullptr, bg ? &bgm : nullptr);
      h.seconds = clock.seconds();
      h.added_peak_bytes = std::max(0.0, proc_status_bytes("VmHWM:") - before);
      const int corners = out.numberofcorners;
      h.corners = corners;
      h.points = std::uint64_t(std::max(0, out.numberofpoints));
      h.tets = std::uint64_t(std::max(0, out.numberoftetrahedra));
      if ((h.points > 0 && !out.pointlist) || (h.tets > 0 && (!out.tetrahedronlist || corners < 4))) {
        h.status = 2;  // an output TetGen should not produce: reported as its internal error
      } else {
        points.assign(out.pointlist, out.pointlist + 3 * h.points);
        tets.resize(4 * h.tets);
        for (std::size_t t = 0; t < h.tets; ++t)
          for (int k = 0; k < 4; ++k) tets[4 * t + k] = std::uint32_t(out.tetrahedronlist[std::size_t(corners) * t + k]);
      }
    }
  } catch (int code) {
    h.status = code == 0 ? 10 : code;
  } catch (const std::bad_alloc&) {
    h.status = 1;
  } catch (...) {
    h.status = 2;
  }
#endif
  if (h.status != 0) {
    h.points = h.tets = 0;
    points.clear();
    tets.clear();
  }
  std::fflush(stdout);
  std::fflush(stderr);
  write_all(data_fd, &h, sizeof h);
  write_all(data_fd, points.data(), points.size() * sizeof(double));
  write_all(data_fd, tets.data(), tets.size() * sizeof(std::uint32_t));
  ::close(data_fd);
  std::_Exit(0);
}

/// The last `n` non-empty lines of `text`, joined with "; ".
std::string log_tail(const std::string& text, std::size_t n) {
  std::vector<std::string> lines;
  std::istringstream s(text);
  for (std::string line; std::getline(s, line);) {
    while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.pop_back();
    if (!line.empty()) lines.push_back(line);
  }
  std::string out;
  for (std::size_t i = lines.size() > n ? lines.size() - n : 0; i < lines.size(); ++i)
    out += (out.empty() ? "" : "; ") + lines[i];
  return out.empty() ? "(no output)" : out;
}

/// TetGen's "<stage> seconds:  <t>" lines.
std::vector<std::pair<std::string, double>> parse_stage_times(const std::string& log) {
  std::vector<std::pair<std::string, double>> stages;
  std::istringstream s(log);
  for (std::string line; std::getline(s, line);) {
    const std::size_t k = line.find(" seconds:");
    if (k == std::string::npos) continue;
    std::size_t b = line.find_first_not_of(' ');
    if (b >= k) continue;
    char* end = nullptr;
    const char* num = line.c_str() + k + 9;
    const double t = std::strtod(num, &end);
    if (end == num) continue;
    stages.push_back({line.substr(b, k - b), t});
  }
  return stages;
}

}  // namespace

TetgenRun run_tetgen(const PreparedSurface& surface, const PointSet& holes, const BackgroundMesh* background,
                     const std::string& switches, double timeout_seconds) {
  if (!tetgen_available()) throw UsageError(without_tetgen_message("run_tetgen"));
  const bool metric = switches.find('m') != std::string::npos;
  if (metric != (background != nullptr))
    throw UsageError("run_tetgen: a background mesh goes with the m switch and only with it");
  if (surface.mesh.num_tris() >= std::size_t(INT32_MAX) || surface.mesh.points.size() >= std::size_t(INT32_MAX))
    throw UsageError("TetGen: the surface is too large for its int ids");
  int data[2], logp[2];
  if (::pipe(data) != 0) throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
  if (::pipe(logp) != 0) {
    ::close(data[0]);
    ::close(data[1]);
    throw Error(std::string("cannot create a pipe: ") + std::strerror(errno));
  }
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t pid = ::fork();
  if (pid < 0) {
    for (int fd : {data[0], data[1], logp[0], logp[1]}) ::close(fd);
    throw Error(std::string("cannot start the TetGen process: ") + std::strerror(errno));
  }
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive kdmesh (it holds no temporaries)
    ::close(data[0]);
    ::close(logp[0]);
    tetgen_child(surface, holes, background, switches, data[1], logp[1]);
  }
  ::close(data[1]);
  ::close(logp[1]);

  // Read both pipes to their ends (TetGen's log may be long: never let either pipe fill).
  std::string payload, log;
  bool timed_out = false;
  const auto deadline = std::chrono::steady_clock::now() +
                        std::chrono::duration<double>(timeout_seconds > 0 ? timeout_seconds : 0);
  int fds[2] = {data[0], logp[0]};
  std::string* sinks[2] = {&payload, &log};
  while (fds[0] >= 0 || fds[1] >= 0) {
    pollfd p[2];
    nfds_t n = 0;
    int which[2];
    for (int k = 0; k < 2; ++k)
      if (fds[k] >= 0) {
        p[n] = {fds[k], POLLIN, 0};
        which[n++] = k;
      }
    int wait_ms = -1;
    if (timeout_seconds > 0 && !timed_out) {
      const double left = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
      wait_ms = left > 0 ? int(std::min(left * 1000 + 1, 1e9)) : 0;
    }
    const int r = ::poll(p, n, wait_ms);
    if (r < 0) {
      if (errno == EINTR) continue;
      ::kill(pid, SIGKILL);
      break;
    }
    if (r == 0) {  // the time limit
      timed_out = true;
      ::kill(pid, SIGKILL);
      continue;
    }
    for (nfds_t i = 0; i < n; ++i) {
      if (!(p[i].revents & (POLLIN | POLLHUP | POLLERR))) continue;
      const int k = which[i];
      char buf[1 << 16];
      const ssize_t got = ::read(fds[k], buf, sizeof buf);
      if (got < 0 && errno == EINTR) continue;
      if (got > 0) {
        sinks[k]->append(buf, std::size_t(got));
      } else {
        ::close(fds[k]);
        fds[k] = -1;
      }
    }
  }
  for (int fd : fds)
    if (fd >= 0) ::close(fd);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }

  TetgenRun run;
  run.log = std::move(log);
  if (timed_out)
    throw Error("TetGen did not finish within the time limit (" + std::to_string(timeout_seconds) +
                " s) and was stopped; last output: " + log_tail(run.log, 3));
  ChildHeader h{};
  const bool complete = payload.size() >= sizeof h &&
                        (std::memcpy(&h, payload.data(), sizeof h), std::memcmp(h.magic, kMagic, sizeof kMagic) == 0);
  if (!WIFEXITED(status) || !complete) {
    std::string why;
    if (WIFSIGNALED(status)) {
      const int sig = WTERMSIG(status);
      why = "crashed (signal " + std::to_string(sig) + ", " + strsignal(sig) + ")";
      if (sig == SIGKILL) why += "; out of memory (the kernel's OOM killer)?";
      if (sig == SIGABRT || sig == SIGSEGV)
        why += "; TetGen 1.5's library error exit crashes the process it runs in, typically on a PLC it "
               "rejects (self-intersecting or nearly touching facets)";
    } else {
      why = "exited with status " + std::to_string(WEXITSTATUS(status)) + " without a result";
    }
    throw Error("TetGen " + why + "; last output: " + log_tail(run.log, 3));
  }
  if (h.status == -1) throw UsageError("TetGen rejected the switches '" + switches + "'");
  if (h.status != 0)
    throw CheckError("TetGen failed on this surface: " + tetgen_error_text(h.status) + " (its code " +
                     std::to_string(h.status) + "); last output: " + log_tail(run.log, 3));
  const std::size_t need = sizeof h + h.points * 3 * sizeof(double) + h.tets * 4 * sizeof(std::uint32_t);
  if (payload.size() != need || h.corners < 4)
    throw Error("TetGen's process returned an incomplete mesh (" + std::to_string(payload.size()) + " of " +
                std::to_string(need) + " bytes)");
  run.seconds = h.seconds;
  run.added_peak_bytes = h.added_peak_bytes;
  run.stages = parse_stage_times(run.log);
  run.mesh.points.xyz.resize(3 * h.points);
  std::memcpy(run.mesh.points.xyz.data(), payload.data() + sizeof h, h.points * 3 * sizeof(double));
  run.mesh.tets.resize(4 * h.tets);
  std::memcpy(run.mesh.tets.data(), payload.data() + sizeof h + h.points * 3 * sizeof(double),
              h.tets * 4 * sizeof(std::uint32_t));
  // TetGen's orientation convention is the opposite of kdmesh's; decide per tet, exactly.
  for (std::size_t t = 0; t < h.tets; ++t) {
    std::uint32_t* v = &run.mesh.tets[4 * t];
    for (int k = 0; k < 4; ++k)
      if (v[k] >= h.points)
        throw Error("TetGen returned tet " + std::to_string(t) + " with an invalid vertex id " + std::to_string(v[k]));
    const PointSet& P = run.mesh.points;
    const int o = pred::orient3d(P.p(v[0]), P.p(v[1]), P.p(v[2]), P.p(v[3]));
    if (o < 0) std::swap(v[0], v[1]);
    if (o == 0) ++run.flat_tets;
  }
  return run;
}

// ---- measures ------------------------------------------------------------------------------

nlohmann::json measure_mesh(const TetMesh& mesh, const SizingField& sizing, double solid_volume) {
  std::vector<TetQuality> per;
  const QualitySummary q = summarize_quality(mesh, &per);
  std::uint64_t below5 = 0, below10 = 0, below12 = 0;
  double volume = 0;
  for (const TetQuality& t : per) {
    below5 += t.min_dihedral < 5;
    below10 += t.min_dihedral < 10;
    below12 += t.min_dihedral < 12;
    volume += t.volume;
  }
  std::vector<bool> used(mesh.points.size(), false);
  for (std::uint32_t v : mesh.tets) used[v] = true;
  const SizeFidelity f = measure_size_fidelity(mesh.points, mesh.tets, sizing);
  return {{"nodes", std::count(used.begin(), used.end(), true)},
          {"tets", mesh.num_tets()},
          {"quality", quality_json(q)},
          {"min_dihedral_below", {{"5", below5}, {"10", below10}, {"12", below12}}},
          {"volume",
           {{"mesh", volume},
            {"solid", solid_volume},
            {"relative_error", solid_volume != 0 ? std::fabs(volume - solid_volume) / std::fabs(solid_volume) : 0.0}}},
          {"size_fidelity", size_fidelity_json(f)}};
}

// ---- the comparison ------------------------------------------------------------------------

namespace {

/// A private scratch directory, removed with everything in it when this goes out of scope.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& parent) {
    namespace fs = std::filesystem;
    std::error_code ec;
    const fs::path base = parent.empty() ? fs::temp_directory_path(ec) : fs::path(parent);
    if (ec) throw OutputError("temporary directory", ec.message());
    for (int i = 0; i < 100 && path_.empty(); ++i) {
      const fs::path p = base / ("kdmesh-compare-" + std::to_string(::getpid()) + "-" + std::to_string(i));
      if (fs::create_directories(p, ec)) path_ = p;
    }
    if (path_.empty()) throw OutputError(base.string(), "cannot create a scratch directory" + (ec ? ": " + ec.message() : ""));
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

std::string fmt_factor(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

double peak_rss_bytes() {
  rusage ru{};
  ::getrusage(RUSAGE_SELF, &ru);
  return 1024.0 * double(ru.ru_maxrss);
}

/// kdmesh's linear tets from its MEDIT copy (corner nodes of quadratic tets).
TetMesh tets_of(const FeMesh& fe) {
  TetMesh m;
  m.points = fe.points;
  const int k = fe.tet_nodes();
  m.tets.reserve(4 * fe.num_tets());
  for (std::size_t t = 0; t < fe.num_tets(); ++t)
    for (int j = 0; j < 4; ++j) m.tets.push_back(fe.tets[std::size_t(k) * t + j]);
  return m;
}

nlohmann::json error_json(ExitCode code, const std::string& message) {
  return {{"type", error_type_name(code)}, {"exit_code", int(code)}, {"message", message}};
}

}  // namespace

TetgenComparison compare_with_tetgen(MeshJob job, const TetgenCompareOptions& options, const MeshJobCallbacks& cb) {
  if (!tetgen_available()) throw UsageError(without_tetgen_message("compare-tetgen"));
  auto log = [&](const std::string& s) {
    if (cb.log) cb.log(s);
  };
  const std::string switches = tetgen_switch_string(options.switches, options.sizing, job.sizing.max_size);
  ScratchDir scratch(options.scratch_dir);
  if (!options.keep_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(options.keep_dir, ec);
    if (ec) throw OutputError(options.keep_dir, "cannot create directory: " + ec.message());
  }

  TetgenComparison c;
  nlohmann::json& rep = c.report;
  rep["job"] = job.name;
  rep["input"] = job.input;
  rep["method"] = {{"tetgen_switches", switches},
                   {"tetgen_sizing", tetgen_sizing_name(options.sizing)},
                   {"tetgen_size_factor", options.size_factor},
                   {"background_spacing", options.background_spacing},
                   {"size", job.sizing.max_size},
                   {"zones", job.sizing.zones.size()}};

  // kdmesh: the job as given, but its outputs replaced by a MEDIT copy of the linear mesh.
  job.vtu = options.keep_dir.empty() ? "" : (std::filesystem::path(options.keep_dir) / "kdmesh.vtu").string();
  job.summary.clear();
  job.nodes.clear();
  job.msh.clear();
  job.inp.clear();
  job.boundary_vtu.clear();
  job.element_order = 1;
  job.medit = scratch.file("kdmesh.mesh");
  log("kdmesh side: meshing " + job.input);
  const MeshJobResult kd = run_mesh_job(job, cb);
  nlohmann::json& k = rep["kdmesh"];
  k["peak_rss_bytes"] = peak_rss_bytes();
  k["summary"] = kd.summary;
  k["seconds"] = kd.summary.contains("seconds") ? kd.summary["seconds"] : nlohmann::json::object();
  if (!kd.ok()) {
    k["status"] = "failed";
    k["error"] = kd.summary.value("error", nlohmann::json::object());
    c.code = kd.code;
    c.error = k["error"].value("message", std::string("the kdmesh job failed"));
    rep["tetgen"] = {{"status", "not run"}, {"switches", switches}};
    return c;
  }
  k["status"] = "ok";
  if (k["summary"].contains("outputs") && k["summary"]["outputs"].is_object()) k["summary"]["outputs"].erase("medit");
  TetMesh kd_mesh = tets_of(read_medit(job.medit));

  // TetGen's input: the same surface, prepared the same way, and the same sizing field.
  nlohmann::json& t = rep["tetgen"];
  t["switches"] = switches;
  Stopwatch clock;
  log("TetGen side: its input (the same prepared surface and sizing field)");
  SurfaceMesh raw = read_surface(job.input);
  if (job.repair.any()) {
    SurfaceRepairReport rr;
    raw = repair_surface(std::move(raw), job.repair, rr);
  }
  SurfaceOptions so;
  so.scale = job.scale;
  const PreparedSurface surface = prepare_surface(std::move(raw), job.input, so);
  const SizingField sizing = build_sizing_field(surface.mesh, job.sizing);
  const SurfaceQuery query(surface.mesh);
  const PointSet holes = void_hole_points(surface, query);
  t["seconds"]["input"] = clock.seconds();
  t["counts"] = {{"input_points", surface.mesh.points.size()},
                 {"input_facets", surface.mesh.num_tris()},
                 {"holes", holes.size()}};

  BackgroundMesh bg;
  if (options.sizing == TetgenSizing::mtr) {
    clock.reset();
    log("TetGen side: background mesh (Delaunay of kdmesh's " + std::to_string(kd_mesh.points.size()) +
        " nodes" + (options.background_spacing > 0 ? " thinned to one per " + fmt_factor(options.background_spacing) + " h" : std::string()) +
        " and the surface points, " + (options.size_factor == 1 ? std::string() : fmt_factor(options.size_factor) + " * ") +
        "h(x) at each)");
    bg = make_background_mesh(kd_mesh.points, surface.mesh, sizing, options.background_spacing);
    if (options.size_factor != 1)
      for (double& x : bg.size) x *= options.size_factor;
    t["seconds"]["background_mesh"] = clock.seconds();
    t["counts"]["background_points"] = bg.points.size();
    t["counts"]["background_tets"] = bg.tets.size() / 4;
  }

  log("TetGen side: tetrahedralize -" + switches);
  TetgenRun run;
  try {
    run = run_tetgen(surface, holes, options.sizing == TetgenSizing::mtr ? &bg : nullptr, switches,
                     options.timeout_seconds);
  } catch (const Error& e) {
    c.code = e.code();
    c.error = e.what();
    t["status"] = "failed";
    t["error"] = error_json(e.code(), e.what());
  }
  bg = BackgroundMesh();

  log("measuring both meshes");
  k["measures"] = measure_mesh(kd_mesh, sizing, surface.volume);
  if (c.ok()) {
    t["status"] = "ok";
    t["seconds"]["tetrahedralize"] = run.seconds;
    nlohmann::json stages = nlohmann::json::array();
    for (const auto& [name, sec] : run.stages) stages.push_back({{"stage", name}, {"seconds", sec}});
    t["seconds"]["stages"] = stages;
    // TetGen's meshing without its reading of the background mesh (an artefact of handing it
    // kdmesh's sizing field), by its own clock: its total minus those two stages.
    double total = -1, background = 0;
    for (const auto& [name, sec] : run.stages) {
      if (name == "Total running") total = sec;
      if (name == "Background mesh reconstruct" || name == "Size interpolating") background += sec;
    }
    if (total >= 0) t["seconds"]["without_background"] = total - background;
    t["added_peak_bytes"] = run.added_peak_bytes;
    t["counts"]["flat_tets"] = run.flat_tets;
    t["measures"] = measure_mesh(run.mesh, sizing, surface.volume);
    if (!options.keep_dir.empty()) {
      const std::string path = (std::filesystem::path(options.keep_dir) / "tetgen.vtu").string();
      log("writing " + path);
      write_vtu(run.mesh, path);
      t["outputs"] = {{"vtu", path}};
    }
  }
  return c;
}

// ---- tables --------------------------------------------------------------------------------

namespace {

std::string fmt(double x, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << x;
  return s.str();
}

std::string sci(double x) {
  std::ostringstream s;
  s << std::scientific << std::setprecision(1) << x;
  return s.str();
}

const nlohmann::json* find(const nlohmann::json& j, std::initializer_list<const char*> path) {
  const nlohmann::json* p = &j;
  for (const char* k : path) {
    if (!p->is_object() || !p->contains(k)) return nullptr;
    p = &(*p)[k];
  }
  return p;
}

double number(const nlohmann::json& j, std::initializer_list<const char*> path, double fallback = 0) {
  const nlohmann::json* p = find(j, path);
  return p && p->is_number() ? p->get<double>() : fallback;
}

}  // namespace

std::string format_comparison(const nlohmann::json& r) {
  std::ostringstream s;
  const nlohmann::json empty = nlohmann::json::object();
  const nlohmann::json& kd = r.contains("kdmesh") ? r["kdmesh"] : empty;
  const nlohmann::json& tg = r.contains("tetgen") ? r["tetgen"] : empty;
  const bool kd_ok = kd.value("status", std::string()) == "ok";
  const bool tg_ok = tg.value("status", std::string()) == "ok";
  s << "compare-tetgen " << r.value("job", std::string()) << " (" << r.value("input", std::string())
    << "): kdmesh vs TetGen 1.5 -" << tg.value("switches", std::string()) << " (sizing "
    << (r.contains("method") ? r["method"].value("tetgen_sizing", std::string()) : std::string()) << ")\n";

  auto row = [&](const std::string& label, const std::string& a, const std::string& b) {
    s << "  " << std::left << std::setw(34) << label << std::right << std::setw(14) << a << std::setw(14) << b
      << "\n";
  };
  auto cell = [](bool ok, const nlohmann::json& side, std::initializer_list<const char*> path, int digits) {
    if (!ok) return std::string("-");
    const nlohmann::json* p = find(side, path);
    if (!p || !p->is_number()) return std::string("-");
    return digits < 0 ? std::to_string(p->get<std::uint64_t>()) : fmt(p->get<double>(), digits);
  };
  s << "\n";
  row("quality", "kdmesh", "TetGen");
  struct Q {
    const char* label;
    std::initializer_list<const char*> path;
    int digits;
  };
  const Q rows[] = {
      {"nodes", {"measures", "nodes"}, -1},
      {"tets", {"measures", "tets"}, -1},
      {"min dihedral (deg)", {"measures", "quality", "min_dihedral"}, 2},
      {"max dihedral (deg)", {"measures", "quality", "max_dihedral"}, 2},
      {"mean radius ratio gamma", {"measures", "quality", "mean_radius_ratio"}, 4},
      {"min radius ratio gamma", {"measures", "quality", "min_radius_ratio"}, 4},
      {"max radius-edge ratio", {"measures", "quality", "max_radius_edge"}, 3},
      {"tets with min dihedral < 5 deg", {"measures", "min_dihedral_below", "5"}, -1},
      {"tets with min dihedral < 10 deg", {"measures", "min_dihedral_below", "10"}, -1},
      {"tets with min dihedral < 12 deg", {"measures", "min_dihedral_below", "12"}, -1},
      {"inverted or flat tets", {"measures", "quality", "inverted"}, -1},
      {"mean edge / target h", {"measures", "size_fidelity", "mean_ratio"}, 3},
  };
  for (const Q& q : rows) row(q.label, cell(kd_ok, kd, q.path, q.digits), cell(tg_ok, tg, q.path, q.digits));
  auto pct = [](bool ok, const nlohmann::json& side) {
    return ok ? fmt(100 * number(side, {"measures", "size_fidelity", "fraction_in_range"}), 1) + "%" : std::string("-");
  };
  row("edges with length in [0.7, 1.4] h", pct(kd_ok, kd), pct(tg_ok, tg));
  auto volerr = [](bool ok, const nlohmann::json& side) {
    return ok ? sci(number(side, {"measures", "volume", "relative_error"})) : std::string("-");
  };
  row("volume error (relative)", volerr(kd_ok, kd), volerr(tg_ok, tg));

  // Time: the stages of each side, next to each other.
  s << "\n";
  std::vector<std::pair<std::string, std::string>> left, right;
  double meshing = 0;
  if (kd.contains("seconds")) {
    const nlohmann::json& sec = kd["seconds"];
    for (const char* st : {"read", "prepare", "features", "sizing", "query", "estimate", "place", "mesh", "improve"})
      if (sec.contains(st)) {
        left.push_back({st, fmt(sec[st].get<double>(), 3)});
        meshing += sec[st].get<double>();
      }
    left.push_back({"= meshing (read..improve)", fmt(meshing, 3)});
    for (const char* st : {"delaunay_check", "mesh_check", "quality", "groups", "write", "total"})
      if (sec.contains(st)) left.push_back({st, fmt(sec[st].get<double>(), 3)});
  }
  if (tg.contains("seconds")) {
    const nlohmann::json& sec = tg["seconds"];
    if (sec.contains("stages"))
      for (const auto& st : sec["stages"]) right.push_back({st.value("stage", std::string()), fmt(st.value("seconds", 0.0), 3)});
    if (sec.contains("tetrahedralize")) right.push_back({"= tetrahedralize (wall)", fmt(sec["tetrahedralize"].get<double>(), 3)});
    if (sec.contains("background_mesh")) right.push_back({"background mesh (not in TetGen's)", fmt(sec["background_mesh"].get<double>(), 3)});
  }
  s << "  " << std::left << std::setw(42) << "time (s): kdmesh stage" << "TetGen stage (its own clock)\n";
  for (std::size_t i = 0; i < std::max(left.size(), right.size()); ++i) {
    std::ostringstream line;
    line << "  ";
    if (i < left.size()) line << std::left << std::setw(28) << left[i].first << std::right << std::setw(10) << left[i].second;
    else line << std::setw(38) << "";
    line << "    ";
    if (i < right.size()) line << std::left << std::setw(36) << right[i].first << std::right << std::setw(10) << right[i].second;
    std::string text = line.str();
    text.erase(text.find_last_not_of(' ') + 1);
    s << text << "\n";
  }
  if (kd_ok && tg_ok) {
    const double tt = number(tg, {"seconds", "tetrahedralize"});
    s << "  meshing time: kdmesh " << fmt(meshing, 2) << " s (read..improve, wall); TetGen " << fmt(tt, 2)
      << " s (tetrahedralize, wall)";
    if (const nlohmann::json* w = find(tg, {"seconds", "without_background"}))
      s << ", " << fmt(w->get<double>(), 2) << " s without reading the background mesh (its clock)";
    s << "\n";
    s << "  peak memory: kdmesh process " << fmt(number(kd, {"peak_rss_bytes"}) / 1048576.0, 0)
      << " MiB, TetGen's call added " << fmt(number(tg, {"added_peak_bytes"}) / 1048576.0, 0) << " MiB\n";
  }
  if (kd_ok && tg_ok) {
    // TetGen reads a size as a circumradius bound: say which factor would match the edge lengths.
    const double rk = number(kd, {"measures", "size_fidelity", "mean_ratio"});
    const double rt = number(tg, {"measures", "size_fidelity", "mean_ratio"});
    const double factor = number(r, {"method", "tetgen_size_factor"}, 1);
    const bool mtr = r.contains("method") && r["method"].value("tetgen_sizing", std::string()) == "mtr";
    if (mtr && rk > 0 && rt > 0 && std::fabs(rt / rk - 1) > 0.05)
      s << "  TetGen's edges are " << fmt(rt / rk, 2) << " x kdmesh's (mean edge / target): --tetgen-size-factor "
        << fmt(factor * rk / rt, 2) << " would match them\n";
  }
  if (kd.contains("error"))
    s << "  kdmesh failed: " << kd["error"].value("message", std::string()) << "\n";
  if (tg.contains("error"))
    s << "  TetGen failed: " << tg["error"].value("message", std::string()) << "\n";
  return s.str();
}

}  // namespace kdmesh
