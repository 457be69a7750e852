// kdmesh bench — the paper's published numbers (Tables 1-15), transcribed from the text in
// ../shared/paper/kd-tree-insertion-sequence.txt, shown beside ours in tables.md.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Measured by the paper's authors on a Pentium Dual-Core E5300 @ 2.6 GHz, Windows XP, 2 GB,
// with CGAL 4.0's Delaunay_triangulation_3 (Sect. 3.1-3.2):
//  - "Kd-tree" and "BRIO": insert() one point at a time in that order, with a search hint
//    (the kd-tree parent for Kd-tree) -- our `cgal kd-bfs` and `cgal brio` runs;
//  - "Hilbert": CGAL's own insert(range) (spatial sort, mixed with BRIO) -- our `cgal range`.
// Times (Tables 1-7) are CPU seconds including the order building; counts (Tables 8-14) are
// calls of CGAL's orientation() and cells found by find_conflicts(), divided by n.
#pragma once
#include <array>
#include <cstddef>

namespace kdmesh::paper {

inline constexpr const char* kLabel = "paper (Pentium Dual-Core, CGAL 4.0)";

/// Tables 1-7: seconds for Kd-tree, BRIO, Hilbert at six sizes.
struct TimeTable {
  int number;
  const char* dist;
  std::array<std::size_t, 6> sizes;
  std::array<std::array<double, 3>, 6> seconds;  ///< [size][Kd-tree, BRIO, Hilbert]
};

inline constexpr std::array<TimeTable, 7> kTimes = {{
    {1, "cube", {100000, 200000, 300000, 400000, 500000, 600000},
     {{{5, 5, 5}, {10, 12, 10}, {14, 16, 16}, {19, 21, 21}, {25, 29, 27}, {31, 32, 32}}}},
    {2, "planes", {300000, 450000, 600000, 750000, 900000, 1050000},
     {{{13, 20, 17}, {20, 29, 26}, {27, 41, 35}, {35, 59, 44}, {41, 63, 54}, {48, 87, 63}}}},
    {3, "paraboloid", {180000, 360000, 540000, 720000, 900000, 1050000},
     {{{8, 14, 11}, {17, 30, 24}, {26, 45, 33}, {36, 51, 44}, {42, 61, 58}, {50, 79, 72}}}},
    {4, "spiral", {360000, 720000, 1080000, 1440000, 1800000, 2160000},
     {{{15, 18, 18}, {30, 38, 36}, {44, 55, 54}, {56, 75, 71}, {69, 92, 89}, {83, 115, 107}}}},
    {5, "disk", {360000, 720000, 1080000, 1440000, 1800000, 2160000},
     {{{17, 30, 23}, {31, 58, 51}, {48, 88, 81}, {63, 125, 113}, {83, 191, 147}, {100, 248, 182}}}},
    {6, "cylinder", {360000, 720000, 1080000, 1440000, 1800000, 2160000},
     {{{17, 26, 21}, {33, 67, 46}, {50, 94, 75}, {68, 146, 112}, {86, 201, 145}, {101, 267, 201}}}},
    {7, "axes", {300000, 450000, 600000, 750000, 900000, 1050000},
     {{{14, 215, 148}, {22, 317, 259}, {25, 496, 397}, {32, 786, 557}, {40, 1079, 743},
       {45, 1385, 938}}}},
}};

/// Tables 8-14: orientation tests and conflicting elements per point, for Kd-tree, BRIO and
/// Hilbert, at the sizes of the matching time table.
struct CountTable {
  int number;
  const char* dist;
  std::array<std::size_t, 6> sizes;
  std::array<std::array<double, 6>, 3> orient;     ///< [Kd-tree, BRIO, Hilbert][size]
  std::array<std::array<double, 6>, 3> conflicts;  ///< [Kd-tree, BRIO, Hilbert][size]
  const char* note;                                ///< transcription remarks, or ""
};

inline constexpr std::array<CountTable, 7> kCounts = {{
    {8, "cube", {100000, 200000, 300000, 400000, 500000, 600000},
     {{{11.787, 11.675, 11.776, 11.7, 11.672, 11.765},
       {16.383, 15.735, 17.776, 16.977, 16.592, 20.106},
       {12.716, 12.852, 13.208, 12.78, 12.656, 12.600}}},
     {{{17.000, 17.035, 17.229, 17.133, 17.143, 17.276},
       {17.103, 17.619, 21.006, 17.988, 19.722, 20.847},
       {18.686, 18.930, 19.023, 18.725, 18.798, 18.821}}},
     ""},
    {9, "planes", {300000, 450000, 600000, 750000, 900000, 1050000},
     {{{11.738, 12.037, 12.192, 12.204, 11.741, 12.151},
       {33.741, 39.254, 40.121, 35.223, 42.091, 36.455},
       {22.966, 23.031, 23.337, 23.626, 23.931, 24.412}}},
     {{{15.738, 15.807, 15.942, 15.902, 15.782, 15.978},
       {18.547, 17.222, 19.043, 17.947, 23.589, 17.954},
       {18.837, 18.748, 18.772, 18.767, 18.803, 18.779}}},
     "the paper prints 500 000 for the second size; Table 2 ran 450 000"},
    {10, "paraboloid", {180000, 360000, 540000, 720000, 900000, 1050000},
     {{{12.024, 12.029, 12.015, 12.026, 11.910, 12.002},
       {34.920, 41.203, 40.449, 41.612, 49.853, 47.911},
       {23.285, 26.649, 28.025, 29.137, 30.181, 31.140}}},
     {{{16.494, 16.415, 16.486, 16.362, 16.288, 16.417},
       {17.015, 17.317, 22.212, 17.731, 19.834, 17.900},
       {17.754, 17.678, 17.666, 17.692, 17.668, 17.675}}},
     "the paper prints 80 000 for the first size; Table 3 ran 180 000"},
    {11, "spiral", {360000, 720000, 1080000, 1440000, 1800000, 2160000},
     {{{11.347, 11.077, 10.836, 10.789, 10.589, 10.527},
       {16.920, 17.801, 21.199, 20.381, 15.947, 18.256},
       {14.703, 14.450, 14.498, 14.641, 14.824, 15.007}}},
     {{{14.587, 13.978, 13.506, 13.156, 12.782, 12.562},
       {16.696, 16.667, 17.758, 16.579, 18.102, 16.316},
       {17.082, 17.047, 17.052, 17.063, 17.033, 16.996}}},
     ""},
    {12, "disk", {360000, 720000, 1080000, 1440000, 1800000, 2160000},
     {{{12.376, 12.593, 12.388, 12.695, 12.491, 12.426},
       {43.863, 75.440, 78.536, 79.689, 91.278, 87.655},
       {34.980, 42.088, 48.379, 54.091, 59.411, 64.467}}},
     {{{15.403, 15.607, 15.716, 15.748, 15.776, 15.826},
       {19.253, 25.219, 24.317, 24.633, 29.626, 21.459},
       {18.886, 19.244, 19.422, 19.460, 19.561, 19.572}}},
     ""},
    {13, "cylinder", {360000, 720000, 1080000, 1440000, 1800000, 2160000},
     {{{11.892, 11.984, 11.907, 12.063, 11.958, 11.976},
       {47.798, 75.891, 89.370, 111.29, 100.86, 92.376},
       {27.241, 35.823, 43.954, 51.756, 59.360, 66.942}}},
     {{{15.971, 16.098, 16.182, 16.213, 16.160, 16.269},
       {20.574, 17.705, 17.483, 23.390, 23.696, 19.205},
       {11.892, 11.984, 11.907, 12.063, 11.958, 11.976}}},
     "the paper's Hilbert conflicts row repeats its Kd-tree orientation row (as printed)"},
    {14, "axes", {300000, 450000, 600000, 750000, 900000, 1050000},
     {{{14.239, 14.868, 14.783, 14.775, 15.129, 13.811},
       {884.11, 1317.2, 1213.7, 1511.3, 1982.1, 1803.3},
       {667.35, 826.76, 954.80, 1077.4, 1189.8, 1288}}},
     {{{15.109, 15.302, 15.348, 15.361, 15.517, 15.318},
       {17.650, 22.323, 18.884, 18.259, 22.504, 26.999},
       {18.977, 19.012, 19.040, 19.031, 19.033, 19.033}}},
     ""},
}};

/// Table 15: seconds to build the Kd-tree and Hilbert orders, cube and cylinder.
struct OrderTable {
  std::array<std::size_t, 7> sizes;
  std::array<double, 7> cube_kd, cube_hilbert, cylinder_kd, cylinder_hilbert;
};

inline constexpr OrderTable kOrderBuild = {
    {500000, 1000000, 1500000, 2000000, 2500000, 3000000, 3500000},
    {1, 2, 2, 3, 4, 5, 6},
    {1, 1, 2, 2, 2, 2, 3},
    {1, 1, 1, 2, 3, 4, 5},
    {1, 1, 2, 2, 2, 3, 3},
};

}  // namespace kdmesh::paper
