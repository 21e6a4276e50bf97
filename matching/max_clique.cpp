// Exact maximum clique: bitset branch and bound with greedy-colouring bounds (BBMC/MCQ family),
// degeneracy order, k-core pruning, greedy initial clique, deadline and threads; plus the
// graduated multi-level search of the paper's §"Graph-based Outlier Pruning".
#include "matching/max_clique.h"

#include "geometry/error.h"

#include <algorithm>
#include <atomic>
#include <climits>
#include <mutex>
#include <string>
#include <thread>

namespace quadrix {

namespace {

using Word = BitsetGraph::Word;
using Clock = std::chrono::steady_clock;
constexpr std::size_t kBits = BitsetGraph::kBitsPerWord;

inline std::size_t count_bits(Word word) { return static_cast<std::size_t>(__builtin_popcountll(word)); }
inline std::size_t lowest_bit(Word word) { return static_cast<std::size_t>(__builtin_ctzll(word)); }

std::size_t count_bits(const Word* words, std::size_t word_count) {
  std::size_t total = 0;
  for (std::size_t w = 0; w < word_count; ++w) total += count_bits(words[w]);
  return total;
}

bool any_bit(const Word* words, std::size_t word_count) {
  for (std::size_t w = 0; w < word_count; ++w)
    if (words[w] != 0) return true;
  return false;
}

void check_vertex(const BitsetGraph& graph, int v, const char* what) {
  if (v < 0 || static_cast<std::size_t>(v) >= graph.vertex_count())
    throw Error(std::string(what) + ": vertex " + std::to_string(v) + " out of range [0, " +
                std::to_string(graph.vertex_count()) + ")");
}

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Core numbers and the smallest-last (peeling) order by Batagelj–Zaversnik bucket sort, O(n²/64 + m).
// removal_order[i] is the i-th vertex peeled; cores along it are non-decreasing.
struct Degeneracy {
  std::vector<std::size_t> core;          // core number per original vertex
  std::vector<std::size_t> removal_order; // original vertices in peeling order
};

Degeneracy compute_degeneracy(const BitsetGraph& graph) {
  const std::size_t n = graph.vertex_count();
  const std::size_t words = graph.words_per_row();
  std::vector<std::size_t> degree(n);
  std::size_t max_degree = 0;
  for (std::size_t v = 0; v < n; ++v) {
    degree[v] = count_bits(graph.row(v), words);
    max_degree = std::max(max_degree, degree[v]);
  }
  std::vector<std::size_t> bin_start(max_degree + 2, 0);
  for (std::size_t v = 0; v < n; ++v) ++bin_start[degree[v] + 1];
  for (std::size_t d = 1; d < bin_start.size(); ++d) bin_start[d] += bin_start[d - 1];
  std::vector<std::size_t> order(n), position(n);
  {
    std::vector<std::size_t> next = bin_start;
    for (std::size_t v = 0; v < n; ++v) {
      position[v] = next[degree[v]]++;
      order[position[v]] = v;
    }
  }
  std::vector<bool> removed(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t v = order[i];
    removed[v] = true;
    const Word* row = graph.row(v);
    for (std::size_t w = 0; w < words; ++w) {
      for (Word bits = row[w]; bits != 0; bits &= bits - 1) {
        const std::size_t u = w * kBits + lowest_bit(bits);
        if (removed[u] || degree[u] <= degree[v]) continue;
        // Move u to the front of its degree bin, then shrink the bin: u's degree drops by one.
        const std::size_t du = degree[u];
        const std::size_t front = bin_start[du];
        const std::size_t w_vertex = order[front];
        if (w_vertex != u) {
          std::swap(order[position[u]], order[front]);
          position[w_vertex] = position[u];
          position[u] = front;
        }
        ++bin_start[du];
        --degree[u];
      }
    }
  }
  return Degeneracy{std::move(degree), std::move(order)};
}

// State shared by the worker threads of one search.
struct SharedSearch {
  const BitsetGraph& graph;                 // renumbered: vertex 0 has the highest core number
  const std::vector<std::size_t>& core;     // core number per renumbered vertex (non-increasing)
  std::size_t lower_bound;                  // cliques smaller than this are not wanted
  std::size_t candidate_count;              // top-level vertices [0, candidate_count) after k-core pruning
  std::optional<Clock::time_point> deadline;
  std::atomic<std::size_t> best_size{0};
  std::atomic<bool> stopped{false};
  std::atomic<std::size_t> next_top_level{0};
  std::atomic<std::uint64_t> branches{0};
  std::mutex best_mutex;
  std::vector<int> best_clique;             // renumbered vertices

  SharedSearch(const BitsetGraph& g, const std::vector<std::size_t>& c, std::size_t bound,
               std::size_t candidates, std::optional<Clock::time_point> stop_time, std::vector<int> incumbent)
      : graph(g), core(c), lower_bound(bound), candidate_count(candidates), deadline(stop_time),
        best_size(incumbent.size()), best_clique(std::move(incumbent)) {}

  // Smallest clique size still worth finding.
  std::size_t needed_size() const {
    return std::max(best_size.load(std::memory_order_relaxed) + 1, lower_bound);
  }

  void offer(const std::vector<int>& clique) {
    std::lock_guard<std::mutex> lock(best_mutex);
    if (clique.size() > best_clique.size()) {
      best_clique = clique;
      best_size.store(clique.size(), std::memory_order_relaxed);
    }
  }

  bool deadline_passed() const { return deadline && Clock::now() >= *deadline; }
};

// One branch-and-bound worker: takes top-level vertices from the shared counter and searches
// the clique containing each one plus earlier (higher-core) neighbours.
class SearchWorker {
 public:
  explicit SearchWorker(SharedSearch& shared)
      : shared_(shared), graph_(shared.graph), words_(graph_.words_per_row()),
        uncoloured_(words_), colour_class_(words_) {
    // A clique has at most degeneracy + 1 vertices, so the recursion depth is bounded: size the
    // per-depth buffers once (references into them must never be invalidated by growth).
    const std::size_t max_depth = (shared.core.empty() ? 0 : shared.core[0]) + 3;
    candidates_.assign(max_depth, std::vector<Word>(words_, 0));
    orders_.resize(max_depth);
    colours_.resize(max_depth);
  }

  void run() {
    const std::size_t n = shared_.candidate_count;
    while (!shared_.stopped.load(std::memory_order_relaxed)) {
      const std::size_t k = shared_.next_top_level.fetch_add(1, std::memory_order_relaxed);
      if (k >= n) break;
      // Low-core vertices first (as MCQ's last-vertex-first): each one's candidates are its
      // earlier neighbours, at most its core number of them.
      const std::size_t vertex = n - 1 - k;
      if (shared_.deadline_passed()) {
        shared_.stopped.store(true);
        break;
      }
      if (shared_.core[vertex] + 1 < shared_.needed_size()) continue;
      const std::size_t active_words = vertex / kBits + 1;
      Word* candidates = candidates_at(0);
      const Word* row = graph_.row(vertex);
      for (std::size_t w = 0; w < active_words; ++w) candidates[w] = row[w];
      candidates[active_words - 1] &= (Word{1} << (vertex % kBits)) - 1;  // only earlier vertices
      if (1 + count_bits(candidates, active_words) < shared_.needed_size()) continue;
      current_.assign(1, static_cast<int>(vertex));
      if (!any_bit(candidates, active_words)) {
        shared_.offer(current_);
        continue;
      }
      expand(0, active_words);
    }
    shared_.branches.fetch_add(branches_, std::memory_order_relaxed);
  }

 private:
  Word* candidates_at(std::size_t depth) { return candidates_[depth].data(); }

  // Greedy sequential colouring of the candidate set (BBMC): vertices of colour >= min_colour are
  // appended to order/colour in non-decreasing colour; the others can never lift the current
  // clique above the incumbent and stay candidates only.
  void colour_candidates(const Word* candidates, std::size_t active_words, std::size_t min_colour,
                         std::vector<int>& order, std::vector<int>& colour) {
    order.clear();
    colour.clear();
    std::size_t remaining = 0;
    for (std::size_t w = 0; w < active_words; ++w) {
      uncoloured_[w] = candidates[w];
      remaining += count_bits(candidates[w]);
    }
    std::size_t first_word = 0;
    for (int colour_index = 1; remaining > 0; ++colour_index) {
      while (uncoloured_[first_word] == 0) ++first_word;
      for (std::size_t w = first_word; w < active_words; ++w) colour_class_[w] = uncoloured_[w];
      for (std::size_t w = first_word; w < active_words; ++w) {
        while (colour_class_[w] != 0) {
          const std::size_t bit = lowest_bit(colour_class_[w]);
          const std::size_t v = w * kBits + bit;
          const Word mask = ~(Word{1} << bit);
          colour_class_[w] &= mask;
          uncoloured_[w] &= mask;
          --remaining;
          const Word* row = graph_.row(v);
          for (std::size_t x = w; x < active_words; ++x) colour_class_[x] &= ~row[x];
          if (static_cast<std::size_t>(colour_index) >= min_colour) {
            order.push_back(static_cast<int>(v));
            colour.push_back(colour_index);
          }
        }
      }
    }
  }

  void expand(std::size_t depth, std::size_t active_words) {
    ++branches_;
    if ((branches_ & 15) == 0 && shared_.deadline_passed()) shared_.stopped.store(true);
    if (shared_.stopped.load(std::memory_order_relaxed)) return;
    Word* candidates = candidates_at(depth);
    Word* next = candidates_at(depth + 1);
    const std::size_t needed = shared_.needed_size();
    const std::size_t min_colour = needed > current_.size() ? needed - current_.size() : 1;
    std::vector<int>& order = orders_[depth];
    std::vector<int>& colour = colours_[depth];
    colour_candidates(candidates, active_words, min_colour, order, colour);
    for (std::size_t index = order.size(); index-- > 0;) {
      if (current_.size() + static_cast<std::size_t>(colour[index]) < shared_.needed_size()) return;
      if (shared_.stopped.load(std::memory_order_relaxed)) return;
      const std::size_t v = static_cast<std::size_t>(order[index]);
      const Word* row = graph_.row(v);
      bool non_empty = false;
      for (std::size_t w = 0; w < active_words; ++w) {
        next[w] = candidates[w] & row[w];
        non_empty |= next[w] != 0;
      }
      current_.push_back(static_cast<int>(v));
      if (!non_empty) {
        if (current_.size() >= shared_.needed_size()) shared_.offer(current_);
      } else {
        expand(depth + 1, active_words);
      }
      current_.pop_back();
      candidates[v / kBits] &= ~(Word{1} << (v % kBits));
    }
  }

  SharedSearch& shared_;
  const BitsetGraph& graph_;
  std::size_t words_;
  std::vector<Word> uncoloured_, colour_class_;
  std::vector<std::vector<Word>> candidates_;  // candidate set per depth
  std::vector<std::vector<int>> orders_, colours_;
  std::vector<int> current_;
  std::uint64_t branches_ = 0;
};

// Greedy clique from each high-core vertex (PMC-style): repeatedly add the eligible candidate of
// highest core (the lowest index in the renumbered graph). Returns false when the deadline passed.
// The first start always runs to a maximal clique, deadline or not (one pass over a row at most per
// added vertex): a search whose deadline expired during the ordering still returns a usable clique.
bool greedy_clique(const BitsetGraph& graph, const std::vector<std::size_t>& core,
                   std::optional<Clock::time_point> deadline, std::vector<int>& best) {
  const std::size_t n = graph.vertex_count();
  const std::size_t words = graph.words_per_row();
  std::vector<Word> candidates(words);
  std::vector<int> clique;
  std::size_t eligible = n;  // vertices with core >= |best|: a prefix of the order
  for (std::size_t start = 0; start < n; ++start) {
    if (core[start] + 1 <= best.size()) break;  // cores are non-increasing along the order
    if (start > 0 && (start & 31) == 0 && deadline && Clock::now() >= *deadline) return false;
    while (eligible > 0 && core[eligible - 1] < best.size()) --eligible;
    const std::size_t active_words = (eligible + kBits - 1) / kBits;
    const Word* row = graph.row(start);
    for (std::size_t w = 0; w < active_words; ++w) candidates[w] = row[w];
    if (eligible % kBits != 0) candidates[active_words - 1] &= (Word{1} << (eligible % kBits)) - 1;
    clique.assign(1, static_cast<int>(start));
    for (;;) {
      std::size_t first_word = 0;
      while (first_word < active_words && candidates[first_word] == 0) ++first_word;
      if (first_word == active_words) break;
      if (clique.size() + count_bits(candidates.data() + first_word, active_words - first_word) <= best.size()) break;
      const std::size_t u = first_word * kBits + lowest_bit(candidates[first_word]);
      clique.push_back(static_cast<int>(u));
      const Word* u_row = graph.row(u);
      for (std::size_t w = first_word; w < active_words; ++w) candidates[w] &= u_row[w];
    }
    if (clique.size() > best.size()) best = clique;
  }
  return true;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// BitsetGraph

BitsetGraph::BitsetGraph(std::size_t vertex_count)
    : vertex_count_(vertex_count), words_per_row_((vertex_count + kBitsPerWord - 1) / kBitsPerWord) {
  if (vertex_count > static_cast<std::size_t>(INT_MAX))
    throw Error("BitsetGraph: vertex_count " + std::to_string(vertex_count) + " exceeds the int vertex range");
  rows_.assign(vertex_count_ * words_per_row_, 0);
}

BitsetGraph BitsetGraph::from_edges(std::size_t vertex_count, const std::vector<std::pair<int, int>>& edges) {
  BitsetGraph graph(vertex_count);
  for (const auto& edge : edges) graph.add_edge(edge.first, edge.second);
  return graph;
}

std::size_t BitsetGraph::edge_count() const { return count_bits(rows_.data(), rows_.size()) / 2; }

double BitsetGraph::density() const {
  if (vertex_count_ < 2) return 0.0;
  const double n = static_cast<double>(vertex_count_);
  return 2.0 * static_cast<double>(edge_count()) / (n * (n - 1.0));
}

void BitsetGraph::add_edge(int u, int v) {
  check_vertex(*this, u, "BitsetGraph::add_edge");
  check_vertex(*this, v, "BitsetGraph::add_edge");
  if (u == v) throw Error("BitsetGraph::add_edge: self-loop on vertex " + std::to_string(u) + " is not allowed");
  add_edge_unchecked(static_cast<std::size_t>(u), static_cast<std::size_t>(v));
}

bool BitsetGraph::has_edge(int u, int v) const {
  check_vertex(*this, u, "BitsetGraph::has_edge");
  check_vertex(*this, v, "BitsetGraph::has_edge");
  const std::size_t column = static_cast<std::size_t>(v);
  return (row(static_cast<std::size_t>(u))[column / kBitsPerWord] >> (column % kBitsPerWord)) & 1u;
}

std::size_t BitsetGraph::degree(int v) const {
  check_vertex(*this, v, "BitsetGraph::degree");
  return count_bits(row(static_cast<std::size_t>(v)), words_per_row_);
}

std::vector<int> BitsetGraph::neighbours(int v) const {
  check_vertex(*this, v, "BitsetGraph::neighbours");
  std::vector<int> result;
  const Word* bits = row(static_cast<std::size_t>(v));
  for (std::size_t w = 0; w < words_per_row_; ++w)
    for (Word word = bits[w]; word != 0; word &= word - 1)
      result.push_back(static_cast<int>(w * kBitsPerWord + lowest_bit(word)));
  return result;
}

bool BitsetGraph::is_clique(const std::vector<int>& vertices) const {
  for (int v : vertices)
    if (v < 0 || static_cast<std::size_t>(v) >= vertex_count_) return false;
  for (std::size_t a = 0; a < vertices.size(); ++a)
    for (std::size_t b = a + 1; b < vertices.size(); ++b)
      if (vertices[a] == vertices[b] || !has_edge(vertices[a], vertices[b])) return false;
  return true;
}

bool BitsetGraph::is_subgraph_of(const BitsetGraph& other) const {
  if (other.vertex_count_ != vertex_count_) return false;
  for (std::size_t i = 0; i < rows_.size(); ++i)
    if ((rows_[i] & ~other.rows_[i]) != 0) return false;
  return true;
}

const char* to_string(CliqueStatus status) {
  switch (status) {
    case CliqueStatus::optimal: return "optimal";
    case CliqueStatus::timeout: return "timeout";
    case CliqueStatus::empty_graph: return "empty_graph";
    case CliqueStatus::no_edges: return "no_edges";
  }
  return "unknown";
}

// ---------------------------------------------------------------------------------------------
// find_maximum_clique

MaxCliqueResult find_maximum_clique(const BitsetGraph& graph, const MaxCliqueOptions& options) {
  const Clock::time_point start = Clock::now();
  if (options.thread_count < 0)
    throw Error("MaxCliqueOptions::thread_count must be >= 0 (0 = hardware concurrency), got " +
                std::to_string(options.thread_count));
  if (!graph.is_clique(options.initial_clique))
    throw Error("MaxCliqueOptions::initial_clique is not a clique of the graph (repeated, out-of-range or "
                "non-adjacent vertices)");

  MaxCliqueResult result;
  const std::size_t n = graph.vertex_count();
  if (n == 0) {
    result.status = CliqueStatus::empty_graph;
    result.statistics.seconds = seconds_since(start);
    return result;
  }
  if (graph.edge_count() == 0) {
    result.clique = options.initial_clique.empty() ? std::vector<int>{0} : options.initial_clique;
    result.status = CliqueStatus::no_edges;
    result.statistics.seconds = seconds_since(start);
    return result;
  }

  // Degeneracy order: renumbered vertex i = original removal_order[n - 1 - i], so vertex 0 is the
  // last peeled (highest core) and every vertex has at most core(v) earlier neighbours.
  const Degeneracy degeneracy = compute_degeneracy(graph);
  std::vector<int> original_of(n), renumbered_of(n);
  std::vector<std::size_t> core(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t original = degeneracy.removal_order[n - 1 - i];
    original_of[i] = static_cast<int>(original);
    renumbered_of[original] = static_cast<int>(i);
    core[i] = degeneracy.core[original];
  }
  result.statistics.degeneracy = core[0];
  BitsetGraph ordered(n);
  for (std::size_t v = 0; v < n; ++v) {
    const Word* row = graph.row(v);
    const std::size_t new_v = static_cast<std::size_t>(renumbered_of[v]);
    for (std::size_t w = 0; w < graph.words_per_row(); ++w)
      for (Word bits = row[w]; bits != 0; bits &= bits - 1)
        ordered.set_half_edge_unchecked(new_v, static_cast<std::size_t>(renumbered_of[w * kBits + lowest_bit(bits)]));
  }

  std::vector<int> incumbent;
  for (int v : options.initial_clique) incumbent.push_back(renumbered_of[static_cast<std::size_t>(v)]);
  bool out_of_time = false;
  if (options.use_initial_heuristic) out_of_time = !greedy_clique(ordered, core, options.deadline, incumbent);
  result.statistics.heuristic_clique_size = incumbent.size();

  std::size_t threads = options.thread_count == 0 ? std::max(1u, std::thread::hardware_concurrency())
                                                  : static_cast<std::size_t>(options.thread_count);
  std::size_t lower_bound = options.lower_bound;
  std::uint64_t branches = 0;
  while (!out_of_time) {
    // k-core pruning: a clique of size s needs core >= s - 1; cores are non-increasing, so the
    // surviving vertices are a prefix of the order.
    const std::size_t needed = std::max(incumbent.size() + 1, lower_bound);
    std::size_t candidates = n;
    while (candidates > 0 && core[candidates - 1] + 1 < needed) --candidates;
    result.statistics.pruned_vertices = n - candidates;

    SharedSearch shared(ordered, core, lower_bound, candidates, options.deadline, incumbent);
    const std::size_t workers = std::max<std::size_t>(1, std::min(threads, candidates));
    result.statistics.threads_used = workers;
    if (workers == 1) {
      SearchWorker(shared).run();
    } else {
      std::vector<std::thread> pool;
      pool.reserve(workers);
      for (std::size_t t = 0; t < workers; ++t) pool.emplace_back([&shared] { SearchWorker(shared).run(); });
      for (std::thread& thread : pool) thread.join();
    }
    branches += shared.branches.load();
    incumbent = shared.best_clique;
    out_of_time = shared.stopped.load();
    // A wrong caller bound (no clique that large) leaves the incumbent below it: search again
    // without the bound so the answer stays exact.
    if (out_of_time || incumbent.size() >= lower_bound) break;
    lower_bound = 0;
  }
  result.statistics.branches = branches;

  if (incumbent.empty()) incumbent.push_back(0);  // any vertex is a clique (no heuristic, deadline before any search)
  result.clique.reserve(incumbent.size());
  for (int v : incumbent) result.clique.push_back(original_of[static_cast<std::size_t>(v)]);
  std::sort(result.clique.begin(), result.clique.end());
  result.status = out_of_time ? CliqueStatus::timeout : CliqueStatus::optimal;
  result.statistics.seconds = seconds_since(start);
  return result;
}

// ---------------------------------------------------------------------------------------------
// Graduated search (paper §"Graph-based Outlier Pruning", graduated PMC)

GraduatedCliqueResult find_graduated_maximum_cliques(const std::vector<BitsetGraph>& levels,
                                                     const MaxCliqueOptions& options) {
  const Clock::time_point start = Clock::now();
  GraduatedCliqueResult result;
  result.levels.reserve(levels.size());
  for (std::size_t k = 0; k < levels.size(); ++k) {
    if (levels[k].vertex_count() != levels[0].vertex_count())
      throw Error("find_graduated_maximum_cliques: level " + std::to_string(k) + " has " +
                  std::to_string(levels[k].vertex_count()) + " vertices, level 0 has " +
                  std::to_string(levels[0].vertex_count()));
    MaxCliqueOptions level_options = options;
    if (k > 0) {
      const std::vector<int>& previous = result.levels.back().clique;
      if (!levels[k].is_clique(previous))
        throw Error("find_graduated_maximum_cliques: the levels are not nested (the clique of level " +
                    std::to_string(k - 1) + " is not a clique of level " + std::to_string(k) +
                    "); build them with ascending thresholds");
      // The previous clique stays valid in this looser graph: it is the incumbent, so a level
      // with no larger clique returns it instead of an empty set.
      level_options.initial_clique = previous;
      level_options.lower_bound = previous.size();
    }
    result.levels.push_back(find_maximum_clique(levels[k], level_options));
  }
  result.seconds = seconds_since(start);
  return result;
}

}  // namespace quadrix
