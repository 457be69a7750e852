// kdmesh — the flip stage of the quality-improvement pass (mesher/improve/flip_pass.h).
// SPDX-License-Identifier: AGPL-3.0-or-later
#include "mesher/improve/flip_pass.h"

#include <algorithm>
#include <atomic>
#include <functional>
#include <limits>
#include <memory>
#include <queue>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include "core/cpu_count.h"
#include "mesher/improve/flip_parts.h"
#include "mesher/improve/improve_flips.h"
#include "mesher/improve/improve_quality.h"
#include "mesher/worker_team.h"

namespace kdmesh {

namespace {

/// Tets taken from the queue at once when several threads choose flips.
constexpr std::size_t kBatch = 64;
/// How far ahead in the sorted first entries a tet's lines are requested.
constexpr std::size_t kAhead = 16;

/// A tet's choice: its best improving flip on the mesh as it stood, and the vertices beyond
/// the tet's own whose stars the choice read (boundary edge removals read a ring end's star).
struct FlipChoice {
  FlipCandidate best;
  bool have = false, is_edge = false, is_boundary = false;
  /// With touching bodies: the new tets stay in the cavity's body (ImproveTets::replace's
  /// region test, made here on the workers; positions and regions do not change in the stage).
  bool in_region = true;
  /// tet_sine of each new tet of `best`, as SineCache::refresh will find it once they are made
  /// (computed on the workers).
  std::vector<double> fresh_q;
  std::uint32_t star_read[6] = {};
  int stars = 0;
  /// The choice needed a star its StarAccess does not allow (left to the stage's serial phase).
  bool deferred = false;
};

/// The best of tet t's edge removals, face removals and (given `boundary`) boundary edge
/// removals that improve the mesh; `cand` is scratch space. Reads only tets that hold a vertex
/// of t or of out.star_read (positions do not change during the flip stage); out.star_read
/// only where `access` allows (else out.deferred).
void choose(const ImproveTets& m, std::uint32_t t, const double* sines, int max_ring,
            const BoundaryContext* boundary, FlipCandidate& cand, FlipChoice& out,
            const StarAccess& access = {}) {
  FlipCandidate& best = out.best;
  best.q_new = -1;
  best.q_old = 0;
  out.have = out.is_edge = out.is_boundary = false;
  out.in_region = true;
  out.deferred = false;
  out.stars = 0;
  m.prefetch_around(t);
  const std::uint32_t* v = m.v(t);
  // Validity (exact orientation, inside tests) is checked last, only for a candidate that
  // would become the best: the same choice as checking every candidate, for less work.
  for (const auto& e : kTetEdge)
    if (edge_removal(m, t, v[e[0]], v[e[1]], max_ring, cand, out.have ? best.q_new : -1, sines,
                     false) &&
        cand.improves() && (!out.have || cand.q_new > best.q_new) && flip_valid(m, cand)) {
      std::swap(best, cand);
      out.have = out.is_edge = true;
    }
  // A face removal is taken only if it improves on the two tets and on the best so far: its
  // evaluation stops at the first new tet that cannot.
  for (int i = 0; i < 4; ++i)
    if (m.adj(t, i) != kImproveNone &&
        face_removal(m, t, i, cand, sines, false,
                     std::max(out.have ? best.q_new : 0.0,
                              std::min(sines[t], sines[m.adj(t, i) >> 2]))) &&
        cand.improves() && (!out.have || cand.q_new > best.q_new) && flip_valid(m, cand)) {
      std::swap(best, cand);
      out.have = true;
      out.is_edge = false;
    }
  if (boundary)
    for (const auto& e : kTetEdge) {
      std::uint32_t star = kImproveNone;
      const bool found = boundary_edge_removal(m, t, v[e[0]], v[e[1]], max_ring, *boundary, cand,
                                               out.have ? best.q_new : -1, sines, &star, access);
      if (star != kImproveNone) out.star_read[out.stars++] = star;
      if (star != kImproveNone && !access.ok(star)) {
        out.deferred = true;
        return;
      }
      if (found && cand.improves() && (!out.have || cand.q_new > best.q_new)) {
        std::swap(best, cand);
        out.have = out.is_boundary = true;
        out.is_edge = false;
      }
    }
  out.fresh_q.clear();
  if (!out.have) return;
  out.in_region = m.fresh_in_region(best.fresh, m.region(best.old[0]));
  for (std::size_t k = 0; k < best.fresh.size(); k += 4)
    out.fresh_q.push_back(tet_sine(m.p(best.fresh[k]), m.p(best.fresh[k + 1]), m.p(best.fresh[k + 2]),
                                   m.p(best.fresh[k + 3])));
}

using Entry = std::tuple<double, std::uint32_t, std::uint32_t>;  // quality, tet, version

/// The flip stage's queue, lowest (quality, tet, version) first: the tets below the threshold
/// when the stage starts, sorted once (on two threads), and a binary heap of the entries pushed
/// later (new tets, tets put back). It pops the same sequence as one heap of all of them, as
/// the order is total, without sifting each of the millions of first entries through a heap of
/// their own size (on the paper gear box the one heap's sift-down took about 2 s of the stage's
/// main thread, in cache misses; the first entries were half of its traffic).
class FlipQueue {
 public:
  FlipQueue(std::vector<Entry> first, WorkerTeam* team) : first_(std::move(first)) {
    const auto mid = first_.begin() + std::ptrdiff_t(first_.size() / 2);
    if (team && team->size() > 1 && first_.size() >= 65536) {
      team->run([&](unsigned w) {
        if (w == 0) std::sort(first_.begin(), mid);
        if (w == 1) std::sort(mid, first_.end());
      });
      std::inplace_merge(first_.begin(), mid, first_.end());
    } else {
      std::sort(first_.begin(), first_.end());
    }
  }
  bool empty() const { return next_ == first_.size() && heap_.empty(); }
  const Entry& top() const { return from_heap() ? heap_.top() : first_[next_]; }
  void pop() {
    if (from_heap()) heap_.pop();
    else ++next_;
  }
  void push(const Entry& e) { heap_.push(e); }
  /// The tet of the sorted first entries `d` places past the next one (kImproveNone if none):
  /// the flip stage starts loading it before its turn.
  std::uint32_t first_ahead(std::size_t d) const {
    return next_ + d < first_.size() ? std::get<1>(first_[next_ + d]) : kImproveNone;
  }

 private:
  bool from_heap() const { return next_ == first_.size() || (!heap_.empty() && heap_.top() < first_[next_]); }
  std::vector<Entry> first_;
  std::size_t next_ = 0;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
};

/// Makes choice c (c.have, its tet still as chosen): replaces the cavity (new slots from
/// `pool` when given), counts it, sets the old and new slots' sines and calls push(entry) for
/// each new tet below `threshold`. False if replace refuses (the faces do not match).
template <class Push>
bool make(ImproveTets& m, SineCache& cache, FlipChoice& c, double threshold, FlipCounts& counts,
          std::vector<std::uint32_t>& created, std::vector<std::uint32_t>* pool, Push&& push) {
  if (!c.in_region || !m.replace(c.best.old, c.best.fresh, &created, c.is_boundary, true, pool))
    return false;
  ++(c.is_boundary ? counts.boundary_flips : c.is_edge ? counts.edge_removals : counts.face_removals);
  // (A freed slot the new tets did not take is dead; the new tets' sines are the choice's.)
  for (std::uint32_t o : c.best.old)
    if (!m.alive(o)) cache.set(o, std::numeric_limits<double>::infinity());
  for (std::size_t j = 0; j < created.size(); ++j) {
    const std::uint32_t n = created[j];
    if (!c.is_boundary) m.mark_inside(n);  // flip_valid passed inside_ok on every one
    const double qn = c.fresh_q[j];
    cache.set(n, qn);
    if (qn < threshold) push(Entry(qn, n, m.version(n)));
  }
  return true;
}

/// One part of a phase of parts: its tets' entries, the entries it leaves (to the next phase
/// or the serial phase), its dead slots and its counts.
struct Part {
  std::vector<Entry> first, left;
  std::vector<std::uint32_t> pool;
  FlipCounts counts;
  std::size_t ops = 0;
};

/// Works part p's queue, worst first, one tet at a time, as the serial phase would on the
/// part alone: a tet not held by the part (parts.holds), or whose choice needs a star outside
/// it, or whose flip needs more slots than the part's pool has, is left.
/// Every tet it reads or changes has its four vertices in the part, so the parts run at once.
void work_part(ImproveTets& m, SineCache& cache, const FlipParts& parts, std::uint8_t p, Part& part,
               double threshold, int max_ring, const BoundaryContext* boundary) {
  FlipQueue queue(std::move(part.first), nullptr);
  const StarAccess access{parts.deep.data(), p};
  const double* sines = cache.q().data();  // (grown: set() does not move it)
  FlipCandidate cand;
  FlipChoice c;
  std::vector<std::uint32_t> created;
  while (!queue.empty()) {
    const Entry e = queue.top();
    queue.pop();
    if (const std::uint32_t a = queue.first_ahead(kAhead); a != kImproveNone) m.prefetch_tet(a);
    const std::uint32_t t = std::get<1>(e);
    if (!m.alive(t) || m.version(t) != std::get<2>(e)) continue;
    if (!parts.holds(p, m.v(t))) {
      part.left.push_back(e);
      continue;
    }
    choose(m, t, sines, max_ring, boundary, cand, c, access);
    if (c.deferred || (c.have && part.pool.size() + c.best.old.size() < c.best.fresh.size() / 4)) {
      part.left.push_back(e);
      continue;
    }
    if (c.have && make(m, cache, c, threshold, part.counts, created, &part.pool,
                       [&](const Entry& n) { queue.push(n); }))
      ++part.ops;
  }
}

/// One phase of parts: the tets `below` split into parts (flip_parts), each part worked apart
/// (work_part), the parts shared out over the team's threads. Appends the entries the parts
/// left to `rest`; returns the flips made. The result depends only on the mesh and the
/// schedule: the parts change disjoint sets of tets, each from its own dead slots.
std::size_t work_parts(ImproveTets& m, SineCache& cache, const std::vector<std::uint32_t>& below,
                       double threshold, int max_ring, const BoundaryContext* boundary,
                       const FlipSchedule& schedule, WorkerTeam* team, FlipCounts& counts,
                       std::vector<Entry>& rest) {
  const FlipParts parts = flip_parts(m, below, schedule.levels(below.size()), team ? team->size() : 1);
  std::vector<Part> part(parts.count);
  for (const std::uint32_t t : below) {
    const std::uint8_t p = parts.deep[m.v(t)[0]];
    (p != kNoPart && parts.holds(p, m.v(t)) ? part[p].first : rest)
        .emplace_back(cache.q()[t], t, m.version(t));
  }
  for (Part& pt : part)
    pt.pool = m.take_slots(std::max<std::size_t>(schedule.min_pool, pt.first.size() / schedule.pool_per));
  cache.grow();
  std::vector<std::uint32_t> order(parts.count);  // largest first, for the threads' balance
  for (std::uint32_t p = 0; p < parts.count; ++p) order[p] = p;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return part[a].first.size() > part[b].first.size(); });
  std::atomic<std::size_t> next{0};
  auto work = [&](unsigned) {
    for (std::size_t k; (k = next.fetch_add(1)) < order.size();)
      work_part(m, cache, parts, std::uint8_t(order[k]), part[order[k]], threshold, max_ring, boundary);
  };
  if (team) team->run(work);
  else work(0);
  std::size_t ops = 0;
  for (Part& pt : part) {  // in part order
    m.give_slots(pt.pool);
    rest.insert(rest.end(), pt.left.begin(), pt.left.end());
    counts.edge_removals += pt.counts.edge_removals;
    counts.face_removals += pt.counts.face_removals;
    counts.boundary_flips += pt.counts.boundary_flips;
    counts.in_parts += pt.ops;
    ops += pt.ops;
  }
  return ops;
}

}  // namespace

std::size_t flip_pass(ImproveTets& m, SineCache& cache, double threshold, int max_ring,
                      FlipCounts& counts, const BoundaryContext* boundary, unsigned threads,
                      const FlipSchedule& schedule) {
  const unsigned asked = threads ? threads : available_cpus();
  // A batch is about half a millisecond of work (64 choices of ~9 us on the gear box's
  // housing), near the cost of starting a thread: the threads are started once, not per batch.
  std::unique_ptr<WorkerTeam> team;
  if (asked > 1) team = std::make_unique<WorkerTeam>(asked);
  std::vector<std::uint32_t> below = cache.below(threshold);
  std::vector<Entry> first;
  std::size_t ops = 0;
  if (schedule.levels(below.size()) > 0) {
    // Phases of parts, each on the tets the one before left (those near its cuts: the next
    // cuts fall elsewhere), while they are enough for one.
    std::vector<std::uint32_t> seeds = std::move(below);
    for (unsigned phase = 0;; ++phase) {
      first.clear();
      ops += work_parts(m, cache, seeds, threshold, max_ring, boundary, schedule, team.get(), counts, first);
      std::erase_if(first, [&m](const Entry& e) {
        return !m.alive(std::get<1>(e)) || m.version(std::get<1>(e)) != std::get<2>(e);
      });
      if (phase + 1 >= schedule.max_phases || schedule.levels(first.size()) == 0) {
        counts.left_by_parts += first.size();
        break;
      }
      seeds.clear();
      for (const Entry& e : first) seeds.push_back(std::get<1>(e));
    }
  } else {
    first.reserve(below.size());
    for (std::uint32_t t : below) first.emplace_back(cache.q()[t], t, m.version(t));
  }
  FlipQueue heap(std::move(first), team.get());
  const unsigned workers = team ? team->size() : 1;
  const std::size_t batch_max = workers > 1 ? kBatch : 1;
  std::vector<Entry> batch;
  std::vector<FlipChoice> choices(batch_max);
  std::vector<std::uint32_t> chosen_at(batch_max), todo;
  std::vector<FlipCandidate> scratch(workers);
  // Choices of tets that went back to the queue (a new tet came first), by (tet, version),
  // with the batch they were made in: reused unless a vertex they read was touched since.
  std::unordered_map<std::uint64_t, std::pair<FlipChoice, std::uint32_t>> carried;
  auto key = [](const Entry& e) { return std::uint64_t(std::get<1>(e)) << 32 | std::get<2>(e); };
  // Per vertex: the last batch in which a tet holding it was replaced (batches count from 1).
  std::vector<std::uint32_t> touched(m.nodes().size_count(), 0);
  std::uint32_t stamp = 0;
  std::vector<std::uint32_t> created;
  while (!heap.empty()) {
    batch.clear();
    while (!heap.empty() && batch.size() < batch_max) {
      const Entry e = heap.top();
      heap.pop();
      if (const std::uint32_t a = heap.first_ahead(kAhead); a != kImproveNone) m.prefetch_tet(a);
      if (m.alive(std::get<1>(e)) && m.version(std::get<1>(e)) == std::get<2>(e))
        batch.push_back(e);
      else if (!carried.empty())
        carried.erase(key(e));
    }
    if (batch.empty()) break;
    for (const Entry& e : batch)  // read after the choices, by this thread
      for (int i = 0; i < 4; ++i) __builtin_prefetch(&touched[m.v(std::get<1>(e))[i]]);
    ++stamp;
    todo.clear();
    for (std::size_t k = 0; k < batch.size(); ++k) {
      const auto it = carried.empty() ? carried.end() : carried.find(key(batch[k]));
      if (it == carried.end()) {
        todo.push_back(std::uint32_t(k));
        chosen_at[k] = stamp;
      } else {
        std::swap(choices[k], it->second.first);
        chosen_at[k] = it->second.second;
        carried.erase(it);
        ++counts.reused;
      }
    }
    // Choose on the mesh as it stands (read only), the tets shared out one at a time.
    const double* sines = cache.q().data();
    if (todo.size() == 1) {
      choose(m, std::get<1>(batch[todo[0]]), sines, max_ring, boundary, scratch[0], choices[todo[0]]);
    } else if (!todo.empty()) {
      std::atomic<std::size_t> next{0};
      team->run([&](unsigned w) {
        for (std::size_t i; (i = next.fetch_add(1)) < todo.size();)
          choose(m, std::get<1>(batch[todo[i]]), sines, max_ring, boundary, scratch[w], choices[todo[i]]);
      });
    }
    // Make them in queue order, as one tet at a time would.
    for (std::size_t k = 0; k < batch.size(); ++k) {
      if (k > 0 && !heap.empty() && heap.top() < batch[k]) {  // a new tet comes first
        counts.requeued += batch.size() - k;
        for (std::size_t j = k; j < batch.size(); ++j) {
          heap.push(batch[j]);
          auto& slot = carried[key(batch[j])];
          std::swap(slot.first, choices[j]);
          slot.second = chosen_at[j];
        }
        break;
      }
      if (k + 1 < batch.size() && choices[k + 1].have)  // the next replace's cavity
        for (std::uint32_t o : choices[k + 1].best.old) m.prefetch_tet(o);
      const auto [q, t, ver] = batch[k];
      if (!m.alive(t) || m.version(t) != ver) continue;
      FlipChoice& c = choices[k];
      bool stale = false;
      for (int i = 0; i < 4; ++i) stale = stale || touched[m.v(t)[i]] >= chosen_at[k];
      for (int s = 0; s < c.stars; ++s) stale = stale || touched[c.star_read[s]] >= chosen_at[k];
      if (stale) {
        choose(m, t, cache.q().data(), max_ring, boundary, scratch[0], c);
        ++counts.chosen_again;
      }
      if (!c.have) continue;
      for (std::uint32_t o : c.best.old)
        for (int i = 0; i < 4; ++i) touched[m.v(o)[i]] = stamp;
      if (make(m, cache, c, threshold, counts, created, nullptr, [&](const Entry& n) { heap.push(n); }))
        ++ops;
    }
  }
  return ops;
}

}  // namespace kdmesh
