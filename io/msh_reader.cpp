// kdmesh — Gmsh MSH reader (4.1 and 2.x, ASCII and binary) into FeMesh.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// The whole file is read into memory and scanned once. Every count is checked against the
// bytes that remain before anything is allocated from it, every node tag an element uses must
// have been defined, and every failure is an InputError naming the line (ASCII) or the byte
// offset (binary data).
#include "io/msh_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "io/file_io.h"
#include "io/text_scanner.h"

namespace kdmesh {

namespace {

/// Gmsh's tet10 node i is VTK's node kGmshTet10[i] (an involution: also the inverse map).
constexpr int kGmshTet10[10] = {0, 1, 2, 3, 4, 5, 6, 7, 9, 8};

struct TypeInfo {
  int dim;
  int order;
  int nodes;
};

/// The element types kdmesh reads; false for any other.
bool type_info(std::int64_t type, TypeInfo& t) {
  switch (type) {
    case 1: t = {1, 1, 2}; return true;
    case 8: t = {1, 2, 3}; return true;
    case 2: t = {2, 1, 3}; return true;
    case 9: t = {2, 2, 6}; return true;
    case 4: t = {3, 1, 4}; return true;
    case 11: t = {3, 2, 10}; return true;
    case 15: t = {0, 0, 1}; return true;
    default: return false;
  }
}

/// Numbers from ASCII tokens or, inside binary sections, from raw words (size_t = 8 bytes,
/// int = 4 bytes, double = 8 bytes; byte-swapped when the file's order is not ours).
class MshIn {
 public:
  explicit MshIn(TextScanner& sc) : sc_(sc) {}
  void set_binary(bool b) { bin_ = b; }
  void set_swap(bool s) { swap_ = s; }
  bool binary() const { return bin_; }

  std::uint64_t size(const char* what) {
    if (!bin_) return sc_.uint64(what);
    return load<std::uint64_t>(what);
  }
  std::int64_t integer(const char* what) {
    if (!bin_) return sc_.int64(what);
    return load<std::int32_t>(what);
  }
  double real(const char* what) {
    if (!bin_) return sc_.real(what);
    const double v = load<double>(what);
    if (!std::isfinite(v)) fail(std::string(what) + " is not finite");
    return v;
  }
  /// A count of items of at least `min_ascii` / `min_binary` bytes each, checked against the
  /// bytes left so that a lying count fails before any allocation.
  std::uint64_t count(const char* what, std::size_t min_ascii, std::size_t min_binary,
                      bool binary_word = true) {
    const bool word = bin_ && binary_word;
    const std::uint64_t n = word ? size(what) : sc_.uint64(what);
    const std::size_t per = word ? min_binary : min_ascii;
    if (n > sc_.remaining() / per)
      fail(std::string(what) + " " + std::to_string(n) + " exceeds what the remaining " +
           std::to_string(sc_.remaining()) + " bytes can hold (truncated or corrupt file)");
    return n;
  }
  /// Binary sections carry no line numbers: their errors give the byte offset instead.
  [[noreturn]] void fail(const std::string& msg) const {
    if (bin_)
      throw InputError(sc_.path(), 0, "byte " + std::to_string(sc_.position()) + ": " + msg);
    sc_.fail(msg);
  }

 private:
  template <class T>
  T load(const char* what) {
    const char* p = sc_.take(sizeof(T), what);
    unsigned char b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    if (swap_) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

  TextScanner& sc_;
  bool bin_ = false;
  bool swap_ = false;
};

/// Elements of one dimension as read (before sorting by tag).
struct ElementList {
  std::vector<std::uint64_t> tag;
  std::vector<std::uint32_t> entity;    ///< elementary tag - 1
  std::vector<std::int64_t> physical;   ///< MSH 2.x: physical tag per element (0 = none)
  std::vector<std::uint32_t> nodes;     ///< point ids, VTK order
};

/// Node tag -> point id (points are ordered by tag).
class NodeMap {
 public:
  /// Builds the map from the tags in file order and returns the permutation
  /// file position -> point id. Throws through `in` on a duplicate tag.
  std::vector<std::uint32_t> build(const std::vector<std::uint64_t>& tags, MshIn& in) {
    const std::size_t n = tags.size();
    std::vector<std::uint32_t> id_of(n);
    const std::uint64_t max_tag = n ? *std::max_element(tags.begin(), tags.end()) : 0;
    dense_ = max_tag <= 4 * std::uint64_t(n) + 1024;
    if (dense_) {
      table_.assign(std::size_t(max_tag) + 1, kNone);
      for (std::size_t i = 0; i < n; ++i) {
        if (table_[tags[i]] != kNone)
          in.fail("node tag " + std::to_string(tags[i]) + " is defined twice");
        table_[tags[i]] = std::uint32_t(i);
      }
      std::uint32_t next = 0;
      for (auto& slot : table_)
        if (slot != kNone) {
          id_of[slot] = next;
          slot = next++;
        }
    } else {
      sorted_.resize(n);
      for (std::size_t i = 0; i < n; ++i) sorted_[i] = {tags[i], std::uint32_t(i)};
      std::sort(sorted_.begin(), sorted_.end());
      for (std::size_t i = 0; i < n; ++i) {
        if (i > 0 && sorted_[i].first == sorted_[i - 1].first)
          in.fail("node tag " + std::to_string(sorted_[i].first) + " is defined twice");
        id_of[sorted_[i].second] = std::uint32_t(i);
        sorted_[i].second = std::uint32_t(i);
      }
    }
    return id_of;
  }
  /// The point id of `tag`, or false if no node has it.
  bool find(std::uint64_t tag, std::uint32_t& id) const {
    if (dense_) {
      if (tag >= table_.size() || table_[tag] == kNone) return false;
      id = table_[tag];
      return true;
    }
    const auto it = std::lower_bound(sorted_.begin(), sorted_.end(),
                                     std::pair<std::uint64_t, std::uint32_t>(tag, 0));
    if (it == sorted_.end() || it->first != tag) return false;
    id = it->second;
    return true;
  }

 private:
  static constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  bool dense_ = true;
  std::vector<std::uint32_t> table_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sorted_;
};

class MshReader {
 public:
  MshReader(std::string_view data, const std::string& path) : sc_(data, path), in_(sc_) {}

  FeMesh read() {
    while (sc_.more()) {
      const std::string_view tok = sc_.token("a section");
      if (tok.size() < 2 || tok[0] != '$')
        sc_.fail("expected a section ('$Name'), found " + quoted(tok));
      const std::string name(tok.substr(1));
      if (name == "MeshFormat") {
        if (version_ != 0) sc_.fail("second $MeshFormat section");
        read_format();
      } else if (version_ == 0) {
        sc_.fail("the file does not start with $MeshFormat (not a Gmsh MSH 2.x / 4.1 file)");
      } else if (name == "PhysicalNames") {
        read_physical_names();
      } else if (name == "Entities" && version_ == 41) {
        read_entities();
      } else if (name == "PartitionedEntities") {
        sc_.fail("partitioned MSH files are not supported");
      } else if (name == "Nodes") {
        if (nodes_read_) sc_.fail("second $Nodes section");
        version_ == 41 ? read_nodes_41() : read_nodes_22();
        finish_nodes();
      } else if (name == "Elements") {
        if (!nodes_read_) sc_.fail("$Elements before $Nodes");
        if (elements_read_) sc_.fail("second $Elements section");
        version_ == 41 ? read_elements_41() : read_elements_22();
        elements_read_ = true;
      } else {
        // Sections kdmesh does not use ($Periodic, $NodeData, $Comments, ...) are skipped.
        const std::uint64_t line = sc_.line();
        if (!sc_.skip_past("$End" + name))
          throw InputError(sc_.path(), line, "section $" + name + " has no $End" + name);
        continue;
      }
      end_section(name);
    }
    if (version_ == 0) sc_.fail("empty file: no $MeshFormat section");
    return assemble();
  }

 private:
  void end_section(const std::string& name) {
    in_.set_binary(false);
    sc_.expect("$End" + name);
  }

  void read_format() {
    const std::string_view v = sc_.token("the MSH version");
    if (v == "4.1")
      version_ = 41;
    else if (v == "2.2" || v == "2.1" || v == "2.0" || v == "2")
      version_ = 22;
    else if (v == "4" || v == "4.0")
      sc_.fail("MSH 4.0 is not supported (re-save the file as MSH 4.1 or 2.2)");
    else
      sc_.fail("unsupported MSH version " + quoted(v) + " (kdmesh reads 4.1 and 2.x)");
    const std::int64_t file_type = sc_.int64("the file type");
    const std::int64_t data_size = sc_.int64("the data size");
    if (file_type != 0 && file_type != 1)
      sc_.fail("file type " + std::to_string(file_type) + " is neither 0 (ASCII) nor 1 (binary)");
    binary_ = file_type == 1;
    if (binary_ && data_size != 8)
      sc_.fail("binary data size " + std::to_string(data_size) + " is not supported (only 8)");
    if (binary_) {
      sc_.end_of_line();
      std::int32_t one;
      std::memcpy(&one, sc_.take(4, "the byte-order word"), 4);
      if (one == 1)
        in_.set_swap(false);
      else if (one == 0x01000000)
        in_.set_swap(true);
      else
        sc_.fail("bad byte-order word in a binary MSH header");
    }
  }

  void read_physical_names() {
    const std::uint64_t n = sc_.count("the number of physical names", sc_.remaining() / 6);
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::int64_t dim = sc_.int64("a physical group dimension");
      const std::int64_t tag = sc_.int64("a physical tag");
      std::string_view name = sc_.rest_of_line();
      if (name.size() < 2 || name.front() != '"' || name.back() != '"')
        sc_.fail("physical name " + quoted(name) + " is not in double quotes");
      names_[{dim, tag}] = std::string(name.substr(1, name.size() - 2));
    }
  }

  void read_entities() {
    if (binary_) sc_.end_of_line();  // binary data starts on the next line
    in_.set_binary(binary_);
    std::uint64_t num[4];
    for (int d = 0; d < 4; ++d) num[d] = in_.count("an entity count", 2, 4);
    for (int d = 0; d < 4; ++d)
      for (std::uint64_t i = 0; i < num[d]; ++i) {
        const std::int64_t tag = in_.integer("an entity tag");
        for (int c = 0; c < (d == 0 ? 3 : 6); ++c) in_.real("an entity coordinate");
        const std::uint64_t nphys = in_.count("a physical tag count", 2, 4);
        std::vector<std::int64_t> phys(nphys);
        for (auto& p : phys) p = in_.integer("a physical tag");
        if (d > 0) {
          const std::uint64_t nb = in_.count("a bounding entity count", 2, 4);
          for (std::uint64_t j = 0; j < nb; ++j) in_.integer("a bounding entity tag");
          if (!phys.empty()) entity_phys_[{d, tag}] = std::move(phys);
        }
      }
  }

  void read_nodes_41() {
    if (binary_) sc_.end_of_line();  // binary data starts on the next line
    in_.set_binary(binary_);
    const std::uint64_t nblocks = in_.count("the number of node blocks", 8, 20);
    const std::uint64_t n = in_.count("the number of nodes", 8, 32);
    in_.size("the minimum node tag");
    in_.size("the maximum node tag");
    tags_.reserve(n);
    xyz_.reserve(3 * n);
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      const std::int64_t dim = in_.integer("a node block dimension");
      in_.integer("a node block entity tag");
      const std::int64_t parametric = in_.integer("a node block parametric flag");
      if (dim < 0 || dim > 3) in_.fail("node block dimension " + std::to_string(dim));
      if (parametric != 0 && parametric != 1)
        in_.fail("node block parametric flag " + std::to_string(parametric) + " is not 0 or 1");
      const std::uint64_t m = in_.count("the number of nodes in a block", 8, 32);
      if (tags_.size() + m > n)
        in_.fail("node blocks hold more nodes than the declared " + std::to_string(n));
      for (std::uint64_t i = 0; i < m; ++i) tags_.push_back(in_.size("a node tag"));
      const int extra = parametric ? int(dim) : 0;
      for (std::uint64_t i = 0; i < m; ++i) {
        for (int c = 0; c < 3; ++c) xyz_.push_back(in_.real("a node coordinate"));
        for (int c = 0; c < extra; ++c) in_.real("a parametric coordinate");
      }
    }
    if (tags_.size() != n)
      in_.fail("node blocks hold " + std::to_string(tags_.size()) + " nodes, the section header "
               "declares " + std::to_string(n));
  }

  void read_nodes_22() {
    const std::uint64_t n = in_.count("the number of nodes", 8, 28, /*binary_word=*/false);
    if (binary_) sc_.end_of_line();
    in_.set_binary(binary_);
    tags_.reserve(n);
    xyz_.reserve(3 * n);
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::int64_t tag = in_.integer("a node tag");
      if (tag < 0) in_.fail("negative node tag " + std::to_string(tag));
      tags_.push_back(std::uint64_t(tag));
      for (int c = 0; c < 3; ++c) xyz_.push_back(in_.real("a node coordinate"));
    }
  }

  void finish_nodes() {
    nodes_read_ = true;
    if (tags_.size() > std::numeric_limits<std::uint32_t>::max()) in_.fail("too many nodes");
    const std::vector<std::uint32_t> id_of = node_map_.build(tags_, in_);
    points_.xyz.resize(xyz_.size());
    for (std::size_t i = 0; i < id_of.size(); ++i)
      std::copy_n(xyz_.begin() + std::ptrdiff_t(3 * i), 3,
                  points_.xyz.begin() + std::ptrdiff_t(3 * std::size_t(id_of[i])));
    std::vector<double>().swap(xyz_);
    std::vector<std::uint64_t>().swap(tags_);
  }

  /// Records one element (node tags in Gmsh order) of type `t`.
  void add_element(const TypeInfo& t, std::int64_t type, std::uint64_t tag, std::int64_t elementary,
                   std::int64_t physical, const std::uint64_t* node_tags) {
    std::uint32_t ids[10];
    for (int i = 0; i < t.nodes; ++i)
      if (!node_map_.find(node_tags[i], ids[i]))
        in_.fail("element " + std::to_string(tag) + " uses node tag " +
                 std::to_string(node_tags[i]) + ", which no node has");
    if (t.dim == 0) return;  // point elements carry nothing kdmesh keeps
    if (order_ == 0) {
      order_ = t.order;
      first_type_ = type;
    } else if (order_ != t.order) {
      in_.fail("element " + std::to_string(tag) + " of type " + std::to_string(type) +
               " is of order " + std::to_string(t.order) + ", but element type " +
               std::to_string(first_type_) + " before it is of order " + std::to_string(order_) +
               " (mixed orders are not supported)");
    }
    if (elementary < 1 || elementary > std::int64_t(std::numeric_limits<std::uint32_t>::max()))
      in_.fail("element " + std::to_string(tag) + " has elementary tag " +
               std::to_string(elementary) + " (kdmesh needs tags >= 1: entity id = tag - 1)");
    ElementList& list = elements_[t.dim];
    list.tag.push_back(tag);
    list.entity.push_back(std::uint32_t(elementary - 1));
    if (version_ == 22) list.physical.push_back(physical);
    for (int i = 0; i < t.nodes; ++i)
      list.nodes.push_back(t.dim == 3 && t.order == 2 ? ids[kGmshTet10[i]] : ids[i]);
  }

  void read_elements_41() {
    if (binary_) sc_.end_of_line();  // binary data starts on the next line
    in_.set_binary(binary_);
    const std::uint64_t nblocks = in_.count("the number of element blocks", 8, 20);
    const std::uint64_t n = in_.count("the number of elements", 4, 16);
    in_.size("the minimum element tag");
    in_.size("the maximum element tag");
    std::uint64_t seen = 0;
    std::uint64_t node_tags[10];
    for (std::uint64_t b = 0; b < nblocks; ++b) {
      const std::int64_t dim = in_.integer("an element block dimension");
      const std::int64_t entity = in_.integer("an element block entity tag");
      const std::int64_t type = in_.integer("an element type");
      TypeInfo t;
      if (!type_info(type, t))
        in_.fail("unsupported element type " + std::to_string(type) +
                 " (kdmesh reads types 1, 2, 4, 8, 9, 11 and 15: lines, triangles, tetrahedra)");
      if (t.dim != dim)
        in_.fail("element type " + std::to_string(type) + " is of dimension " +
                 std::to_string(t.dim) + ", its block says " + std::to_string(dim));
      const std::uint64_t m =
          in_.count("the number of elements in a block", 2 * std::size_t(t.nodes + 1),
                    8 * std::size_t(t.nodes + 1));
      seen += m;
      if (seen > n) in_.fail("element blocks hold more elements than the declared " + std::to_string(n));
      for (std::uint64_t i = 0; i < m; ++i) {
        const std::uint64_t tag = in_.size("an element tag");
        for (int j = 0; j < t.nodes; ++j) node_tags[j] = in_.size("a node tag");
        add_element(t, type, tag, entity, 0, node_tags);
      }
    }
    if (seen != n)
      in_.fail("element blocks hold " + std::to_string(seen) + " elements, the section header "
               "declares " + std::to_string(n));
  }

  void read_elements_22() {
    const std::uint64_t n = in_.count("the number of elements", 8, 16, /*binary_word=*/false);
    if (binary_) sc_.end_of_line();
    in_.set_binary(binary_);
    std::uint64_t node_tags[10];
    std::uint64_t done = 0;
    while (done < n) {
      // Binary: a header (type, count, number of tags) before each run of one type.
      std::int64_t type = 0, run = 1, ntags = 0;
      if (binary_) {
        type = in_.integer("an element type");
        run = in_.integer("an element count");
        ntags = in_.integer("a tag count");
        if (run < 1 || std::uint64_t(run) > n - done)
          in_.fail("element run of " + std::to_string(run) + " exceeds the declared " +
                   std::to_string(n) + " elements");
      }
      for (std::int64_t r = 0; r < run; ++r, ++done) {
        const std::int64_t tag = in_.integer("an element tag");
        if (!binary_) {
          type = in_.integer("an element type");
          ntags = in_.integer("a tag count");
        }
        TypeInfo t;
        if (!type_info(type, t))
          in_.fail("element " + std::to_string(tag) + ": unsupported element type " +
                   std::to_string(type) +
                   " (kdmesh reads types 1, 2, 4, 8, 9, 11 and 15: lines, triangles, tetrahedra)");
        if (ntags < 0 || ntags > 64)
          in_.fail("element " + std::to_string(tag) + ": tag count " + std::to_string(ntags));
        std::int64_t physical = 0, elementary = 0;
        for (std::int64_t j = 0; j < ntags; ++j) {
          const std::int64_t v = in_.integer("an element tag value");
          if (j == 0) physical = v;
          if (j == 1) elementary = v;
        }
        if (ntags < 2 && t.dim > 0)
          in_.fail("element " + std::to_string(tag) + " has no elementary tag (" +
                   std::to_string(ntags) + " tags)");
        for (int j = 0; j < t.nodes; ++j) {
          const std::int64_t v = in_.integer("a node tag");
          if (v < 0) in_.fail("element " + std::to_string(tag) + ": negative node tag");
          node_tags[j] = std::uint64_t(v);
        }
        if (tag < 0) in_.fail("negative element tag " + std::to_string(tag));
        add_element(t, type, std::uint64_t(tag), elementary, physical, node_tags);
      }
    }
  }

  /// Sorts the elements of dimension d by tag and, for MSH 2.x, drops the per-physical copies;
  /// moves them into `conn` / `entity`.
  void finish_elements(int d, std::vector<std::uint32_t>& conn, std::vector<std::uint32_t>& entity) {
    ElementList& list = elements_[d];
    const std::size_t n = list.tag.size();
    if (n == 0) return;
    const std::size_t nn = list.nodes.size() / n;
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return list.tag[a] < list.tag[b]; });
    std::vector<char> keep(n, 1);
    if (version_ == 22) {
      // Copies share entity and nodes; among equal ones keep the earliest in tag order.
      std::vector<std::uint32_t> rank(n);
      for (std::size_t i = 0; i < n; ++i) rank[order[i]] = std::uint32_t(i);
      std::vector<std::uint32_t> by_key(n);
      std::iota(by_key.begin(), by_key.end(), 0u);
      auto key_less = [&](std::uint32_t a, std::uint32_t b) {
        if (list.entity[a] != list.entity[b]) return list.entity[a] < list.entity[b];
        const int c = std::memcmp(&list.nodes[a * nn], &list.nodes[b * nn], nn * sizeof(std::uint32_t));
        if (c != 0) return c < 0;
        return rank[a] < rank[b];
      };
      std::sort(by_key.begin(), by_key.end(), key_less);
      for (std::size_t i = 1; i < n; ++i) {
        const std::uint32_t a = by_key[i - 1], b = by_key[i];
        if (list.entity[a] == list.entity[b] &&
            std::memcmp(&list.nodes[a * nn], &list.nodes[b * nn], nn * sizeof(std::uint32_t)) == 0)
          keep[b] = 0;
      }
    }
    for (const std::uint32_t e : order) {
      if (!keep[e]) continue;
      conn.insert(conn.end(), list.nodes.begin() + std::ptrdiff_t(e * nn),
                  list.nodes.begin() + std::ptrdiff_t((e + 1) * nn));
      entity.push_back(list.entity[e]);
    }
  }

  FeMesh assemble() {
    FeMesh mesh;
    mesh.points = std::move(points_);
    mesh.order = order_ == 0 ? 1 : order_;

    // Groups: (physical tag, dim) -> entity ids, from $Entities (4.1) or the elements (2.x).
    std::map<std::pair<std::int64_t, int>, std::set<std::uint32_t>> groups;
    for (int d = 1; d <= 3; ++d) {
      const ElementList& list = elements_[d];
      std::set<std::uint32_t> present(list.entity.begin(), list.entity.end());
      if (version_ == 41) {
        for (const auto& [key, phys] : entity_phys_)
          if (key.first == d && key.second >= 1 &&
              present.count(std::uint32_t(key.second - 1)))
            for (const std::int64_t p : phys) groups[{p, d}].insert(std::uint32_t(key.second - 1));
      } else {
        for (std::size_t i = 0; i < list.physical.size(); ++i)
          if (list.physical[i] != 0) groups[{list.physical[i], d}].insert(list.entity[i]);
      }
    }
    for (const auto& [key, ents] : groups) {
      FeGroup g;
      g.dim = key.second;
      const auto it = names_.find({key.second, key.first});
      g.name = it != names_.end() ? it->second : "physical_" + std::to_string(key.first);
      g.entities.assign(ents.begin(), ents.end());
      mesh.groups.push_back(std::move(g));
    }

    finish_elements(3, mesh.tets, mesh.tet_entity);
    finish_elements(2, mesh.faces, mesh.face_entity);
    finish_elements(1, mesh.edges, mesh.edge_entity);
    return mesh;
  }

  TextScanner sc_;
  MshIn in_;
  int version_ = 0;  ///< 41 or 22 once $MeshFormat is read
  bool binary_ = false;
  bool nodes_read_ = false, elements_read_ = false;
  std::map<std::pair<std::int64_t, std::int64_t>, std::string> names_;        ///< (dim, tag)
  std::map<std::pair<int, std::int64_t>, std::vector<std::int64_t>> entity_phys_;  ///< (dim, tag)
  std::vector<std::uint64_t> tags_;  ///< node tags in file order (until finish_nodes)
  std::vector<double> xyz_;          ///< coordinates in file order (until finish_nodes)
  NodeMap node_map_;
  PointSet points_;
  int order_ = 0;
  std::int64_t first_type_ = 0;
  ElementList elements_[4];
};

}  // namespace

FeMesh read_msh(const std::string& path) {
  const std::string data = read_whole_file(path);
  MshReader reader(data, path);
  return reader.read();
}

}  // namespace kdmesh
