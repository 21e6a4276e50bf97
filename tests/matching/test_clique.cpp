// Maximum clique (paper §"Graph-based Outlier Pruning"): the bitset graph, the exact solver against
// a brute-force search and against igraph, threads, deadline, lower bounds, and the graduated
// multi-level search.
#include "matching/max_clique.h"

#include "geometry/error.h"

#include <gtest/gtest.h>
#include <igraph/igraph.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>
#include <vector>

namespace quadrix {
namespace {

// G(n, p) with a fixed generator.
BitsetGraph random_graph(std::size_t n, double p, std::mt19937& random) {
  BitsetGraph graph(n);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t u = 0; u < n; ++u)
    for (std::size_t v = u + 1; v < n; ++v)
      if (uniform(random) < p) graph.add_edge_unchecked(u, v);
  return graph;
}

// Exhaustive clique enumeration on <= 32 vertices (no bounds): every clique is extended by every
// later common neighbour.
void enumerate_cliques(const std::vector<std::uint32_t>& adjacency, std::uint32_t candidates, std::size_t size,
                       std::size_t& best) {
  best = std::max(best, size);
  while (candidates != 0) {
    const int v = __builtin_ctz(candidates);
    candidates &= candidates - 1;
    enumerate_cliques(adjacency, candidates & adjacency[static_cast<std::size_t>(v)], size + 1, best);
  }
}

std::size_t brute_force_clique_number(const BitsetGraph& graph) {
  const std::size_t n = graph.vertex_count();
  std::vector<std::uint32_t> adjacency(n, 0);
  for (std::size_t v = 0; v < n; ++v) adjacency[v] = static_cast<std::uint32_t>(graph.row(v)[0]);
  std::size_t best = 0;
  const std::uint32_t all = n == 32 ? 0xffffffffu : ((1u << n) - 1u);
  enumerate_cliques(adjacency, all, 0, best);
  return best;
}

// igraph's clique number of the same graph (the oracle; tests only).
std::size_t igraph_clique_size(const BitsetGraph& graph) {
  igraph_vector_int_t edges;
  igraph_vector_int_init(&edges, 0);
  for (std::size_t u = 0; u < graph.vertex_count(); ++u)
    for (int v : graph.neighbours(static_cast<int>(u)))
      if (static_cast<std::size_t>(v) > u) {
        igraph_vector_int_push_back(&edges, static_cast<igraph_integer_t>(u));
        igraph_vector_int_push_back(&edges, v);
      }
  igraph_t oracle;
  igraph_create(&oracle, &edges, static_cast<igraph_integer_t>(graph.vertex_count()), IGRAPH_UNDIRECTED);
  igraph_integer_t clique_number = 0;
  igraph_clique_number(&oracle, &clique_number);
  igraph_destroy(&oracle);
  igraph_vector_int_destroy(&edges);
  return static_cast<std::size_t>(clique_number);
}

void expect_sorted_clique(const BitsetGraph& graph, const MaxCliqueResult& result) {
  EXPECT_TRUE(std::is_sorted(result.clique.begin(), result.clique.end()));
  EXPECT_TRUE(graph.is_clique(result.clique));
}

// ---------------------------------------------------------------------------------------------
// BitsetGraph

TEST(BitsetGraph, EdgeListConstructionAndQueries) {
  const BitsetGraph graph = BitsetGraph::from_edges(70, {{0, 1}, {1, 0}, {1, 69}, {64, 2}, {5, 6}});
  EXPECT_EQ(graph.vertex_count(), 70u);
  EXPECT_EQ(graph.words_per_row(), 2u);
  EXPECT_EQ(graph.edge_count(), 4u);  // {0,1} given twice is stored once
  EXPECT_TRUE(graph.has_edge(69, 1));
  EXPECT_TRUE(graph.has_edge(2, 64));
  EXPECT_FALSE(graph.has_edge(0, 2));
  EXPECT_EQ(graph.degree(1), 2u);
  EXPECT_EQ(graph.neighbours(1), (std::vector<int>{0, 69}));
  EXPECT_NEAR(graph.density(), 2.0 * 4.0 / (70.0 * 69.0), 1e-15);
  EXPECT_TRUE(graph.is_clique({0, 1}));
  EXPECT_FALSE(graph.is_clique({0, 1, 69}));
  EXPECT_FALSE(graph.is_clique({1, 1}));
  EXPECT_FALSE(graph.is_clique({0, 70}));
  EXPECT_TRUE(graph.is_clique({}));
}

TEST(BitsetGraph, BadInputThrows) {
  EXPECT_THROW(BitsetGraph::from_edges(3, {{0, 3}}), Error);
  EXPECT_THROW(BitsetGraph::from_edges(3, {{-1, 2}}), Error);
  EXPECT_THROW(BitsetGraph::from_edges(3, {{2, 2}}), Error);
  const BitsetGraph graph(4);
  EXPECT_THROW(graph.has_edge(0, 4), Error);
  EXPECT_THROW(graph.degree(-1), Error);
}

TEST(BitsetGraph, SubgraphRelation) {
  const BitsetGraph small = BitsetGraph::from_edges(5, {{0, 1}});
  const BitsetGraph large = BitsetGraph::from_edges(5, {{0, 1}, {2, 3}});
  EXPECT_TRUE(small.is_subgraph_of(large));
  EXPECT_FALSE(large.is_subgraph_of(small));
  EXPECT_FALSE(small.is_subgraph_of(BitsetGraph(6)));
}

// ---------------------------------------------------------------------------------------------
// Solver vs oracles

TEST(MaxClique, MatchesBruteForceOnThousandsOfSmallRandomGraphs) {
  std::mt19937 random(20240601);
  const double densities[] = {0.05, 0.2, 0.4, 0.6, 0.8, 0.95};
  int cases = 0;
  for (int round = 0; round < 500; ++round) {
    for (double p : densities) {
      const std::size_t n = 1 + static_cast<std::size_t>(round % 20);
      const BitsetGraph graph = random_graph(n, p, random);
      const MaxCliqueResult result = find_maximum_clique(graph);
      const std::size_t expected = brute_force_clique_number(graph);
      ASSERT_EQ(result.size(), expected) << "n=" << n << " p=" << p << " round=" << round;
      expect_sorted_clique(graph, result);
      ASSERT_TRUE(result.status == CliqueStatus::optimal || result.status == CliqueStatus::no_edges);
      ++cases;
    }
  }
  EXPECT_EQ(cases, 3000);
}

TEST(MaxClique, WithoutHeuristicStillMatchesBruteForce) {
  std::mt19937 random(77);
  for (int round = 0; round < 600; ++round) {
    const std::size_t n = 2 + static_cast<std::size_t>(round % 19);
    const BitsetGraph graph = random_graph(n, 0.1 + 0.8 * (round % 9) / 8.0, random);
    MaxCliqueOptions options;
    options.use_initial_heuristic = false;
    const MaxCliqueResult result = find_maximum_clique(graph, options);
    ASSERT_EQ(result.size(), brute_force_clique_number(graph)) << "round " << round;
    expect_sorted_clique(graph, result);
  }
}

TEST(MaxClique, MatchesIgraphOnHundredsOfMediumGraphs) {
  std::mt19937 random(4242);
  struct Setting {
    std::size_t n;
    double p;
    int count;
  };
  // Densities where igraph (the oracle) stays fast at these sizes.
  const Setting settings[] = {{100, 0.05, 40}, {150, 0.1, 40}, {200, 0.2, 40}, {250, 0.3, 30}, {300, 0.02, 40},
                              {300, 0.1, 30},  {400, 0.05, 30}, {120, 0.5, 30}, {80, 0.7, 20}};
  int cases = 0;
  for (const Setting& setting : settings) {
    for (int i = 0; i < setting.count; ++i) {
      const BitsetGraph graph = random_graph(setting.n, setting.p, random);
      const MaxCliqueResult result = find_maximum_clique(graph);
      ASSERT_EQ(result.size(), igraph_clique_size(graph)) << "n=" << setting.n << " p=" << setting.p << " i=" << i;
      ASSERT_EQ(result.status, CliqueStatus::optimal);
      expect_sorted_clique(graph, result);
      ++cases;
    }
  }
  EXPECT_EQ(cases, 300);
}

TEST(MaxClique, FindsPlantedCliqueInSparseGraph) {
  std::mt19937 random(9);
  for (int round = 0; round < 10; ++round) {
    BitsetGraph graph = random_graph(500, 0.05, random);
    std::vector<int> planted(500);
    for (int v = 0; v < 500; ++v) planted[static_cast<std::size_t>(v)] = v;
    std::shuffle(planted.begin(), planted.end(), random);
    planted.resize(25);
    for (std::size_t a = 0; a < planted.size(); ++a)
      for (std::size_t b = a + 1; b < planted.size(); ++b)
        graph.add_edge(planted[a], planted[b]);
    std::sort(planted.begin(), planted.end());
    const MaxCliqueResult result = find_maximum_clique(graph);
    EXPECT_EQ(result.status, CliqueStatus::optimal);
    EXPECT_EQ(result.clique, planted);  // a random extra clique of 25 in G(500, 0.05) is impossible in practice
    EXPECT_GT(result.statistics.pruned_vertices, 0u);  // k-core pruning removes most of the sparse part
  }
}

TEST(MaxClique, MultiThreadedEqualsSingleThreadedSize) {
  std::mt19937 random(31337);
  for (int round = 0; round < 40; ++round) {
    const std::size_t n = 150 + static_cast<std::size_t>(round) * 5;
    const BitsetGraph graph = random_graph(n, 0.1 + 0.02 * (round % 10), random);
    const MaxCliqueResult single = find_maximum_clique(graph);
    for (int threads : {2, 4}) {
      MaxCliqueOptions options;
      options.thread_count = threads;
      const MaxCliqueResult parallel = find_maximum_clique(graph, options);
      ASSERT_EQ(parallel.size(), single.size()) << "round " << round << " threads " << threads;
      ASSERT_EQ(parallel.status, CliqueStatus::optimal);
      expect_sorted_clique(graph, parallel);
    }
  }
  MaxCliqueOptions automatic;
  automatic.thread_count = 0;
  std::mt19937 other(5);
  const BitsetGraph graph = random_graph(200, 0.3, other);
  EXPECT_EQ(find_maximum_clique(graph, automatic).size(), find_maximum_clique(graph).size());
}

TEST(MaxClique, DeadlineReturnsValidCliqueWithTimeoutStatus) {
  std::mt19937 random(8);
  // Dense G(500, 0.9): proving optimality takes far longer than the 20 ms budget.
  const BitsetGraph hard = random_graph(500, 0.9, random);
  for (int threads : {1, 2}) {
    MaxCliqueOptions options;
    options.thread_count = threads;
    options.deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(20);
    const MaxCliqueResult result = find_maximum_clique(hard, options);
    EXPECT_EQ(result.status, CliqueStatus::timeout);
    EXPECT_GE(result.size(), 2u);
    expect_sorted_clique(hard, result);
  }
  // A deadline already passed: still a valid non-empty clique, status timeout.
  for (bool heuristic : {true, false}) {
    MaxCliqueOptions options;
    options.use_initial_heuristic = heuristic;
    options.deadline = std::chrono::steady_clock::now() - std::chrono::seconds(1);
    const MaxCliqueResult result = find_maximum_clique(hard, options);
    EXPECT_EQ(result.status, CliqueStatus::timeout);
    EXPECT_GE(result.size(), 1u);
    expect_sorted_clique(hard, result);
  }
}

TEST(MaxClique, LowerBoundsAndInitialCliques) {
  std::mt19937 random(1234);
  for (int round = 0; round < 200; ++round) {
    const std::size_t n = 5 + static_cast<std::size_t>(round % 16);
    const BitsetGraph graph = random_graph(n, 0.5, random);
    const std::size_t omega = brute_force_clique_number(graph);
    for (std::size_t bound : {omega - 1, omega, omega + 2}) {  // below, exact, wrong (too high)
      for (bool heuristic : {true, false}) {
        MaxCliqueOptions options;
        options.lower_bound = bound;
        options.use_initial_heuristic = heuristic;
        const MaxCliqueResult result = find_maximum_clique(graph, options);
        ASSERT_EQ(result.size(), omega) << "round " << round << " bound " << bound;
        ASSERT_EQ(result.status, CliqueStatus::optimal);
        expect_sorted_clique(graph, result);
      }
    }
    // A maximum clique given as the incumbent is kept (the search finds nothing larger).
    const std::vector<int> maximum = find_maximum_clique(graph).clique;
    MaxCliqueOptions seeded;
    seeded.initial_clique = maximum;
    seeded.lower_bound = maximum.size();
    seeded.use_initial_heuristic = false;
    ASSERT_EQ(find_maximum_clique(graph, seeded).clique, maximum);
  }
}

TEST(MaxClique, DegenerateGraphsAreStatusesNotCrashes) {
  const MaxCliqueResult empty = find_maximum_clique(BitsetGraph(0));
  EXPECT_EQ(empty.status, CliqueStatus::empty_graph);
  EXPECT_TRUE(empty.clique.empty());
  const MaxCliqueResult isolated = find_maximum_clique(BitsetGraph(7));
  EXPECT_EQ(isolated.status, CliqueStatus::no_edges);
  EXPECT_EQ(isolated.clique, std::vector<int>{0});
  const MaxCliqueResult single_edge = find_maximum_clique(BitsetGraph::from_edges(7, {{3, 5}}));
  EXPECT_EQ(single_edge.status, CliqueStatus::optimal);
  EXPECT_EQ(single_edge.clique, (std::vector<int>{3, 5}));
  EXPECT_STREQ(to_string(CliqueStatus::timeout), "timeout");
}

TEST(MaxClique, MisuseThrows) {
  const BitsetGraph graph = BitsetGraph::from_edges(4, {{0, 1}, {1, 2}});
  MaxCliqueOptions not_a_clique;
  not_a_clique.initial_clique = {0, 2};
  EXPECT_THROW(find_maximum_clique(graph, not_a_clique), Error);
  MaxCliqueOptions out_of_range;
  out_of_range.initial_clique = {9};
  EXPECT_THROW(find_maximum_clique(graph, out_of_range), Error);
  MaxCliqueOptions negative_threads;
  negative_threads.thread_count = -1;
  EXPECT_THROW(find_maximum_clique(graph, negative_threads), Error);
}

// ---------------------------------------------------------------------------------------------
// Graduated search

// Nested levels: every pair gets a random weight; level k keeps the pairs with weight <= its threshold.
std::vector<BitsetGraph> nested_levels(std::size_t n, const std::vector<double>& thresholds, double edge_probability,
                                       std::mt19937& random) {
  std::vector<BitsetGraph> levels(thresholds.size(), BitsetGraph(n));
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (std::size_t u = 0; u < n; ++u)
    for (std::size_t v = u + 1; v < n; ++v) {
      const double weight = uniform(random) / edge_probability;
      for (std::size_t k = 0; k < thresholds.size(); ++k)
        if (weight <= thresholds[k]) levels[k].add_edge_unchecked(u, v);
    }
  return levels;
}

TEST(GraduatedClique, LevelsAreExactValidMonotoneAndNeverEmpty) {
  std::mt19937 random(2718);
  int equal_size_levels = 0;
  for (int round = 0; round < 150; ++round) {
    const std::size_t n = 10 + static_cast<std::size_t>(round % 60) * 3;
    // Thresholds close together give many levels whose clique is no larger than the previous one.
    const std::vector<double> thresholds = round % 2 == 0 ? std::vector<double>{0.2, 0.4, 0.6, 0.8}
                                                          : std::vector<double>{0.5, 0.51, 0.52, 0.53};
    const std::vector<BitsetGraph> levels = nested_levels(n, thresholds, 0.3, random);
    const GraduatedCliqueResult graduated = find_graduated_maximum_cliques(levels);
    ASSERT_EQ(graduated.levels.size(), levels.size());
    for (std::size_t k = 0; k < levels.size(); ++k) {
      const MaxCliqueResult& level = graduated.levels[k];
      ASSERT_FALSE(level.clique.empty()) << "round " << round << " level " << k;
      expect_sorted_clique(levels[k], level);
      ASSERT_EQ(level.size(), find_maximum_clique(levels[k]).size()) << "round " << round << " level " << k;
      if (k > 0) {
        ASSERT_GE(level.size(), graduated.levels[k - 1].size());
        if (level.size() == graduated.levels[k - 1].size()) ++equal_size_levels;
      }
      if (levels[k].edge_count() > 0) {
        EXPECT_GE(level.size(), 2u);
      }
    }
  }
  EXPECT_GT(equal_size_levels, 50);  // the pitfall case was exercised
}

TEST(GraduatedClique, IdenticalLevelsKeepTheirClique) {
  std::mt19937 random(99);
  const BitsetGraph graph = random_graph(120, 0.2, random);
  const std::vector<BitsetGraph> levels(4, graph);
  const GraduatedCliqueResult graduated = find_graduated_maximum_cliques(levels);
  const std::size_t omega = find_maximum_clique(graph).size();
  for (const MaxCliqueResult& level : graduated.levels) {
    EXPECT_EQ(level.size(), omega);
    EXPECT_EQ(level.status, CliqueStatus::optimal);
    EXPECT_EQ(level.clique, graduated.levels.front().clique);
  }
}

TEST(GraduatedClique, EdgelessFirstLevelAndMisuse) {
  std::vector<BitsetGraph> levels{BitsetGraph(5), BitsetGraph::from_edges(5, {{1, 2}}),
                                  BitsetGraph::from_edges(5, {{1, 2}, {0, 3}, {0, 4}, {3, 4}})};
  const GraduatedCliqueResult graduated = find_graduated_maximum_cliques(levels);
  EXPECT_EQ(graduated.levels[0].status, CliqueStatus::no_edges);
  EXPECT_EQ(graduated.levels[0].size(), 1u);
  EXPECT_EQ(graduated.levels[1].clique, (std::vector<int>{1, 2}));
  EXPECT_EQ(graduated.levels[2].clique, (std::vector<int>{0, 3, 4}));
  EXPECT_TRUE(find_graduated_maximum_cliques({}).levels.empty());

  const std::vector<BitsetGraph> different_sizes{BitsetGraph(5), BitsetGraph(6)};
  EXPECT_THROW(find_graduated_maximum_cliques(different_sizes), Error);
  const std::vector<BitsetGraph> not_nested{BitsetGraph::from_edges(4, {{0, 1}}), BitsetGraph::from_edges(4, {{2, 3}})};
  EXPECT_THROW(find_graduated_maximum_cliques(not_nested), Error);
}

TEST(GraduatedClique, SharedDeadlineKeepsEveryLevelValid) {
  std::mt19937 random(66);
  const std::vector<BitsetGraph> levels = nested_levels(400, {0.85, 0.9, 0.95}, 1.0, random);
  MaxCliqueOptions options;
  options.deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(10);
  const GraduatedCliqueResult graduated = find_graduated_maximum_cliques(levels, options);
  for (std::size_t k = 0; k < levels.size(); ++k) {
    EXPECT_EQ(graduated.levels[k].status, CliqueStatus::timeout);
    EXPECT_GE(graduated.levels[k].size(), 2u);
    expect_sorted_clique(levels[k], graduated.levels[k]);
    if (k > 0) {
      EXPECT_GE(graduated.levels[k].size(), graduated.levels[k - 1].size());
    }
  }
  // A deadline already past when the search starts (a slow machine, a sanitizer build) still gives
  // each level the greedy clique of its highest-core vertex, never a lone vertex of a dense graph.
  options.deadline = std::chrono::steady_clock::now();
  const GraduatedCliqueResult expired = find_graduated_maximum_cliques(levels, options);
  for (std::size_t k = 0; k < levels.size(); ++k) {
    EXPECT_EQ(expired.levels[k].status, CliqueStatus::timeout);
    EXPECT_GE(expired.levels[k].size(), 2u);
    expect_sorted_clique(levels[k], expired.levels[k]);
  }
}

}  // namespace
}  // namespace quadrix
