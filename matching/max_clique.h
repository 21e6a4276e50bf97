// Exact maximum clique on dense undirected graphs, and the graduated multi-level search of the
// paper's §"Graph-based Outlier Pruning" (Quadric Matching): the maximum clique of each
// compatibility graph G_1 ⊆ G_2 ⊆ … ⊆ G_Kg is an inlier candidate set I*_k, and each level's clique
// size is a lower bound for the next level (|C_1| ≤ |C_2| ≤ … ≤ |C_Kg|).
//
// The solver is our own (the paper's peers use PMC, which is GPL and not packaged): bitset branch
// and bound with greedy-colouring bounds (San Segundo's BBMC / Tomita's MCQ family), a degeneracy
// (k-core) vertex order, k-core pre-pruning against the lower bound, a greedy initial clique, a
// caller lower bound, a steady_clock deadline and an optional split of the top-level branches
// across threads that share the incumbent.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

namespace quadrix {

/// Undirected simple graph as adjacency bitsets: row v holds one bit per vertex (64-bit words),
/// bit u set when {u, v} is an edge. Suited to dense graphs of up to a few tens of thousands of
/// vertices (memory n² / 8 bytes). Self-loops are never stored.
class BitsetGraph {
 public:
  /// One machine word of a bitset row.
  using Word = std::uint64_t;
  /// Number of bits per word.
  static constexpr std::size_t kBitsPerWord = 64;

  /// A graph with `vertex_count` vertices and no edges.
  explicit BitsetGraph(std::size_t vertex_count = 0);

  /// A graph from an edge list; throws quadrix::Error on a vertex out of range or a self-loop.
  /// Repeated edges (in either direction) are stored once.
  static BitsetGraph from_edges(std::size_t vertex_count, const std::vector<std::pair<int, int>>& edges);

  /// Number of vertices n.
  std::size_t vertex_count() const { return vertex_count_; }
  /// Number of 64-bit words in one row: ceil(n / 64).
  std::size_t words_per_row() const { return words_per_row_; }
  /// Number of undirected edges (counted by popcount, O(n² / 64)).
  std::size_t edge_count() const;
  /// Edge density 2m / (n (n - 1)); 0 for graphs with fewer than two vertices.
  double density() const;

  /// Adds the undirected edge {u, v}; throws quadrix::Error on out-of-range vertices or u == v.
  void add_edge(int u, int v);
  /// Adds {u, v} without checks (u != v, both in range); for hot construction loops.
  void add_edge_unchecked(std::size_t u, std::size_t v) {
    rows_[u * words_per_row_ + v / kBitsPerWord] |= Word{1} << (v % kBitsPerWord);
    rows_[v * words_per_row_ + u / kBitsPerWord] |= Word{1} << (u % kBitsPerWord);
  }
  /// Sets bit v in row u only (half of an edge); the caller must also set bit u of row v.
  void set_half_edge_unchecked(std::size_t u, std::size_t v) {
    rows_[u * words_per_row_ + v / kBitsPerWord] |= Word{1} << (v % kBitsPerWord);
  }
  /// True when {u, v} is an edge; throws quadrix::Error on out-of-range vertices.
  bool has_edge(int u, int v) const;
  /// Degree of vertex v (popcount of its row); throws quadrix::Error when out of range.
  std::size_t degree(int v) const;
  /// Neighbours of v in increasing order; throws quadrix::Error when out of range.
  std::vector<int> neighbours(int v) const;
  /// Pointer to the words_per_row() words of row v (no range check).
  const Word* row(std::size_t v) const { return rows_.data() + v * words_per_row_; }
  /// Mutable pointer to row v (no range check); keep the matrix symmetric with a zero diagonal.
  Word* mutable_row(std::size_t v) { return rows_.data() + v * words_per_row_; }

  /// True when the vertices are distinct, in range and pairwise adjacent (the empty set and a
  /// single vertex are cliques).
  bool is_clique(const std::vector<int>& vertices) const;
  /// True when every edge of this graph is also an edge of `other` (same vertex count required,
  /// otherwise false): the nesting G_k ⊆ G_k+1 of the multi-level compatibility graphs.
  bool is_subgraph_of(const BitsetGraph& other) const;

 private:
  std::size_t vertex_count_ = 0;
  std::size_t words_per_row_ = 0;
  std::vector<Word> rows_;  // row-major, vertex_count_ rows of words_per_row_ words
};

/// Outcome of one maximum-clique search.
enum class CliqueStatus {
  optimal,      ///< the search finished: the clique is a maximum clique
  timeout,      ///< the deadline passed: the clique is the best found (valid, maybe not maximum)
  empty_graph,  ///< the graph has no vertices: the clique is empty
  no_edges,     ///< vertices but no edges: the clique is a single vertex (a maximum clique)
};

/// Readable name of a status ("optimal", "timeout", "empty_graph", "no_edges").
const char* to_string(CliqueStatus status);

/// Options of find_maximum_clique.
struct MaxCliqueOptions {
  /// A clique of at least this many vertices is known to exist (the paper's graduated PMC: the
  /// previous level's clique size). Branches that cannot reach it are pruned, and vertices whose
  /// core number is below lower_bound - 1 are removed up front. A clique of exactly this size is
  /// still returned (never an empty set). If the bound is wrong (no such clique), the solver
  /// detects it and searches again without it, so the result stays exact.
  std::size_t lower_bound = 0;
  /// A clique known in this graph, used as the first incumbent (e.g. the previous level's clique,
  /// valid in the next, looser graph). Throws quadrix::Error if it is not a clique.
  std::vector<int> initial_clique;
  /// Stop time: past it the solver returns the best clique found with status timeout.
  std::optional<std::chrono::steady_clock::time_point> deadline;
  /// Worker threads sharing the top-level branches and the incumbent (0 = hardware concurrency).
  int thread_count = 1;
  /// Greedy clique from every high-core vertex before branching (a strong first incumbent).
  bool use_initial_heuristic = true;
};

/// Search statistics of one maximum-clique run.
struct MaxCliqueStatistics {
  std::uint64_t branches = 0;            ///< branch-and-bound nodes expanded (all threads)
  double seconds = 0.0;                  ///< wall-clock time of the call
  std::size_t pruned_vertices = 0;       ///< vertices removed by k-core pruning before branching
  std::size_t degeneracy = 0;            ///< largest core number (clique size ≤ degeneracy + 1)
  std::size_t heuristic_clique_size = 0; ///< size of the incumbent before branching
  std::size_t threads_used = 1;          ///< worker threads actually started
};

/// Result of one maximum-clique search.
struct MaxCliqueResult {
  std::vector<int> clique;          ///< clique vertices, sorted ascending
  CliqueStatus status = CliqueStatus::empty_graph;  ///< see CliqueStatus
  MaxCliqueStatistics statistics;   ///< search statistics
  /// Number of clique vertices.
  std::size_t size() const { return clique.size(); }
};

/// Exact maximum clique of `graph` (paper §"Graph-based Outlier Pruning": the maximum clique of a
/// compatibility graph is the largest mutually consistent correspondence set I*). Throws
/// quadrix::Error on invalid options (initial_clique not a clique, negative thread_count).
MaxCliqueResult find_maximum_clique(const BitsetGraph& graph, const MaxCliqueOptions& options = {});

/// Result of the graduated multi-level search: one entry per level, in level order.
struct GraduatedCliqueResult {
  std::vector<MaxCliqueResult> levels;  ///< clique of level k = inlier candidate set I*_k
  double seconds = 0.0;                 ///< wall-clock time of all levels
};

/// Graduated maximum-clique search over nested graphs G_1 ⊆ G_2 ⊆ … (paper §"Graph-based Outlier
/// Pruning", graduated PMC): levels are solved in order, each seeded with the previous level's
/// clique as incumbent and its size as lower bound, so sizes are monotone and a level whose maximum
/// clique is no larger still returns a clique (the previous one, valid in the looser graph).
/// `options.lower_bound` and `options.initial_clique` seed the first level only; the deadline
/// applies to the whole sequence. Throws quadrix::Error when the levels differ in vertex count or
/// are not nested (the previous clique is not a clique in the next level).
GraduatedCliqueResult find_graduated_maximum_cliques(const std::vector<BitsetGraph>& levels,
                                                     const MaxCliqueOptions& options = {});

}  // namespace quadrix
