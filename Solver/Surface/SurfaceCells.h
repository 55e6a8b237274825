// The pieces of the surface extraction that the CPU (SurfaceExtraction.cpp) and the GPU
// (Cuda/CudaSurface.cu) share: the sampling grid and its blocks, the colour function at a node,
// the cut of a cell into triangles, and the fields at a vertex. Written once, and compiled on the
// GPU without fused multiply-adds, so that both give the same mesh bit for bit.
//
// Order of the output, on both: triangles by block (in block-key order), by cell within a block
// (z, y, x), by tetrahedron and by triangle within a cell; vertices by the key of the grid edge
// they lie on, vertexKey(), which orders them by the block of the edge's lower node, then that
// node within the block, then the edge's direction: each block's vertices are a contiguous run,
// so the GPU can number them with a scan instead of a sort.
#pragma once

#include "Grid.h"
#include "HostDevice.h"
#include "Kernels.h"
#include "SurfaceTypes.h"
#include "Vec3.h"

#include <cmath>
#include <cstdint>

namespace pbf
{
namespace surface
{

constexpr int kBlock = 8;                                         // cells per block edge
constexpr int kBlockNodes = (kBlock + 1) * (kBlock + 1) * (kBlock + 1); // nodes a block samples
constexpr int kBlockCells = kBlock * kBlock * kBlock;

PBF_HD PBF_INLINE std::int64_t lesser(std::int64_t a, std::int64_t b) { return a < b ? a : b; }
PBF_HD PBF_INLINE std::int64_t greater(std::int64_t a, std::int64_t b) { return a > b ? a : b; }

// The sampling grid: node (i, j, k) at origin + (i, j, k) cell, computed by this one expression
// wherever it is needed, so that a node shared by two blocks has the same bits in both.
struct NodeGrid
{
  Vec3d origin;
  double cell = 0;
  std::int64_t n[3] = { 0, 0, 0 }; // nodes per axis
  std::int64_t blocks[3] = { 0, 0, 0 };
  double pad = 0; // how far the grid reaches beyond the domain [m]

  PBF_HD Vec3d at(std::int64_t i, std::int64_t j, std::int64_t k) const
  {
    return origin + Vec3d{ static_cast<double>(i) * cell, static_cast<double>(j) * cell,
                      static_cast<double>(k) * cell };
  }
  PBF_HD std::uint64_t blockKey(std::int64_t bx, std::int64_t by, std::int64_t bz) const
  {
    return (static_cast<std::uint64_t>(bz) * static_cast<std::uint64_t>(blocks[1]) +
             static_cast<std::uint64_t>(by)) *
      static_cast<std::uint64_t>(blocks[0]) +
      static_cast<std::uint64_t>(bx);
  }
  PBF_HD void blockOf(std::uint64_t key, std::int64_t b[3]) const
  {
    const auto bx = static_cast<std::uint64_t>(blocks[0]), by = static_cast<std::uint64_t>(blocks[1]);
    b[0] = static_cast<std::int64_t>(key % bx);
    b[1] = static_cast<std::int64_t>((key / bx) % by);
    b[2] = static_cast<std::int64_t>(key / (bx * by));
  }
  PBF_HD std::uint64_t blockCount() const
  {
    return static_cast<std::uint64_t>(blocks[0]) * static_cast<std::uint64_t>(blocks[1]) *
      static_cast<std::uint64_t>(blocks[2]);
  }
};

// The grid of a run's surface: the domain (where the particles are) padded by h and two nodes,
// so that the colour is below any level at the grid's faces and the surface closes inside it.
// Anchored at the domain, it is the same grid on every rank of a decomposed run. Throws
// InvalidInput naming SurfaceResolution when it would hold more than 1e15 nodes.
NodeGrid makeNodeGrid(const Parameters& parameters, const SurfaceOptions& options);
// Cells of the given size (h, or the anisotropic kernels' reach) over the same region, which the
// particles are sorted into.
GridGeometry<double> particleCells(const NodeGrid& grid, const Parameters& parameters, double cell);

// A node's place in its block's (kBlock + 1)^3 samples, and a cell's in its kBlock^3 cells.
PBF_HD PBF_INLINE int nodeSlot(int i, int j, int k)
{
  return (k * (kBlock + 1) + j) * (kBlock + 1) + i;
}
PBF_HD PBF_INLINE int cellSlot(int i, int j, int k)
{
  return (k * kBlock + j) * kBlock + i;
}

// The output order of the vertex on the grid edge from node (i, j, k) along the direction bits
// dir (x 1, y 2, z 4): the block the node lies in, the node within it, the direction.
PBF_HD PBF_INLINE std::uint64_t vertexKey(
  const NodeGrid& g, std::int64_t i, std::int64_t j, std::int64_t k, int dir)
{
  const std::uint64_t block = g.blockKey(i / kBlock, j / kBlock, k / kBlock);
  const int local = cellSlot(static_cast<int>(i % kBlock), static_cast<int>(j % kBlock),
    static_cast<int>(k % kBlock));
  return (block * kBlockCells + static_cast<std::uint64_t>(local)) * 8 + static_cast<std::uint64_t>(dir);
}

// The blocks that hold a node within h of a particle at x, per axis [first, last] (a node on a
// block's face belongs to both blocks).
PBF_HD PBF_INLINE void blocksNear(
  const NodeGrid& g, double h, const Vec3d& x, std::int64_t first[3], std::int64_t last[3])
{
  const Vec3d q = x - g.origin;
  const double c[3] = { q.x, q.y, q.z };
  for (int a = 0; a < 3; ++a)
  {
    const auto i0 = static_cast<std::int64_t>(::ceil((c[a] - h) / g.cell));
    const auto i1 = static_cast<std::int64_t>(::floor((c[a] + h) / g.cell));
    first[a] = greater(0, i0 > 0 ? (i0 - 1) / kBlock : 0);
    last[a] = lesser(g.blocks[a] - 1, greater(i1, 0) / kBlock);
  }
}

// The particles sorted into cells of h (Green 2008), in double; within a cell by position.
struct CellParticles
{
  GridGeometry<double> geometry;
  const std::uint32_t* offsets = nullptr; // cellCount + 1
  const Vec3d* x = nullptr;
  // Anisotropic kernels (SurfaceOptions::anisotropic): per sorted particle the metric M (xx, xy,
  // xz, yy, yz, zz) of its kernel, W(r) = W_poly6(sqrt(r^T M r)); null: isotropic.
  const double* m = nullptr;
};

// r^T M r for the symmetric M (xx, xy, xz, yy, yz, zz), and M r into mr.
PBF_HD PBF_INLINE double metricSquare(const double* m, const Vec3d& r, Vec3d& mr)
{
  mr = { m[0] * r.x + m[1] * r.y + m[2] * r.z, m[1] * r.x + m[3] * r.y + m[4] * r.z,
    m[2] * r.x + m[4] * r.y + m[5] * r.z };
  return dot(r, mr);
}

// Calls visit(j) for the sorted particles of the 27 cells around q's cell, in a fixed order.
template <class Visit>
PBF_HD PBF_INLINE void forEachParticleNear(const CellParticles& p, const Vec3d& q, Visit&& visit)
{
  const GridGeometry<double>& g = p.geometry;
  const int cx = g.clampedCell(q.x, g.origin.x, g.nx);
  const int cy = g.clampedCell(q.y, g.origin.y, g.ny);
  const int cz = g.clampedCell(q.z, g.origin.z, g.nz);
  const int x0 = cx > 0 ? cx - 1 : 0, x1 = cx + 1 < g.nx ? cx + 1 : g.nx - 1;
  const int z1 = cz + 1 < g.nz ? cz + 1 : g.nz - 1, y1 = cy + 1 < g.ny ? cy + 1 : g.ny - 1;
  for (int z = cz > 0 ? cz - 1 : 0; z <= z1; ++z)
  {
    for (int y = cy > 0 ? cy - 1 : 0; y <= y1; ++y)
    {
      const std::size_t row = (static_cast<std::size_t>(z) * g.ny + y) * g.nx;
      const std::uint32_t end = p.offsets[row + x1 + 1];
      for (std::uint32_t j = p.offsets[row + x0]; j < end; ++j)
      {
        visit(j);
      }
    }
  }
}

// The colour function phi(q) = sum_j (m / rho_0) W_poly6(q - x_j).
PBF_HD PBF_INLINE double colour(
  const CellParticles& p, const Kernels<double>& kernels, double volume, const Vec3d& q)
{
  double phi = 0;
  if (p.m)
  {
    forEachParticleNear(p, q, [&](std::uint32_t j) {
      Vec3d mr;
      phi += kernels.poly6(metricSquare(p.m + 6 * static_cast<std::size_t>(j), q - p.x[j], mr));
    });
  }
  else
  {
    forEachParticleNear(p, q, [&](std::uint32_t j) {
      const Vec3d r = q - p.x[j];
      phi += kernels.poly6(dot(r, r));
    });
  }
  return phi * volume;
}

// The colour clipped by the solids (SurfaceSolids): min(phi, iso + d / cell) over the solids.
PBF_HD PBF_INLINE double clipped(double phi, const DistanceGridView<double>* solids, int count,
  const Vec3d& q, double iso, double inverseCell)
{
  for (int s = 0; s < count; ++s)
  {
    const double wall = iso + solids[s].at(q, nullptr) * inverseCell;
    phi = wall < phi ? wall : phi;
  }
  return phi;
}

// ---- Anisotropic kernels (Yu & Turk 2013) ----------------------------------------------------
// Each particle's kernel is stretched along the principal axes of its neighbours within h: flat at
// a flat free surface (smoother water), thin along a sheet. The axes' lengths follow the
// neighbours' standard deviations along them, the shortest at least half the longest (Yu & Turk's
// k_r = 4, on lengths: 2), scaled to a product of 1 so that the kernel keeps its volume and the
// level its meaning; a particle with fewer than 3/4 of a full neighbourhood's count (Yu & Turk's
// N_eps = 25 at h = 2 s) keeps the round kernel. The longest axis is then at most 4^(1/3) h: how
// far the kernels reach.
// Yu & Turk also pull each kernel's centre towards its neighbours' weighted mean, x_bar = (1 -
// lambda) x + lambda mean with lambda = 0.9. Measured on a sphere of fluid of radius 20 s, that
// shrinks the surface by up to 0.67 s (0.25 s on a flat face; 0.5 s at lambda = 0.25), past the
// half spacing the surface is held to, while the shapes alone make a flat face three times
// smoother (Testing/Solver/SurfaceTest.cpp): lambda is 0 here, the centres the particles'.
constexpr double kCentreBlend = 0.0;
constexpr double kStretchRatio = 2.0;
constexpr double kAnisotropicReach = 1.5875; // >= 4^(1/3) = 1.58740...

// How far a particle's kernel reaches, in h.
inline double reachFactor(const SurfaceOptions& options)
{
  return options.anisotropic ? kAnisotropicReach : 1.0;
}

// The eigenvalues and unit eigenvectors (columns of v, rows first) of the symmetric 3 x 3 matrix
// a (xx, xy, xz, yy, yz, zz), by cyclic Jacobi rotations: a fixed sequence of IEEE operations, so
// the host and the device agree to the bit.
PBF_HD PBF_INLINE void symmetricEigen(const double* a, double* values, double* v)
{
  double m[3][3] = { { a[0], a[1], a[2] }, { a[1], a[3], a[4] }, { a[2], a[4], a[5] } };
  for (int i = 0; i < 9; ++i)
  {
    v[i] = i % 4 == 0 ? 1.0 : 0.0;
  }
  for (int sweep = 0; sweep < 12; ++sweep)
  {
    const double off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
    const double diagonal = m[0][0] * m[0][0] + m[1][1] * m[1][1] + m[2][2] * m[2][2];
    if (!(off > 1e-30 * diagonal))
    {
      break;
    }
    for (int pq = 0; pq < 3; ++pq)
    {
      const int p = pq == 2 ? 1 : 0, q = pq == 0 ? 1 : 2;
      if (m[p][q] == 0.0)
      {
        continue;
      }
      // The rotation that zeroes m[p][q] (Numerical Recipes' form, the smaller angle).
      const double theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
      const double t =
        (theta >= 0 ? 1.0 : -1.0) / ((theta >= 0 ? theta : -theta) + sqrt(theta * theta + 1.0));
      const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
      for (int k = 0; k < 3; ++k)
      {
        const double mkp = m[k][p], mkq = m[k][q];
        m[k][p] = c * mkp - s * mkq;
        m[k][q] = s * mkp + c * mkq;
      }
      for (int k = 0; k < 3; ++k)
      {
        const double mpk = m[p][k], mqk = m[q][k];
        m[p][k] = c * mpk - s * mqk;
        m[q][k] = s * mpk + c * mqk;
      }
      for (int k = 0; k < 3; ++k)
      {
        const double vkp = v[3 * k + p], vkq = v[3 * k + q];
        v[3 * k + p] = c * vkp - s * vkq;
        v[3 * k + q] = s * vkp + c * vkq;
      }
    }
  }
  values[0] = m[0][0];
  values[1] = m[1][1];
  values[2] = m[2][2];
}

// The cube root of x > 0 from IEEE operations alone (the libraries' cbrt differ in the last bit
// between the host and CUDA): x = m 2^(3e) with m in [1/8, 1) exactly, then Newton's iteration
// for m^(1/3) from 1 (six steps: it converges quadratically from within a factor of 2).
PBF_HD PBF_INLINE double cubeRoot(double x)
{
  int exponent = 0;
  double m = frexp(x, &exponent); // x = m 2^exponent, m in [1/2, 1)
  int e = exponent >= 0 ? exponent / 3 : -((-exponent + 2) / 3);
  m = ldexp(m, exponent - 3 * e); // in [1/2, 4)
  double y = 1.0;
  for (int i = 0; i < 8; ++i)
  {
    y = y - (y * y * y - m) / (3.0 * y * y);
  }
  return ldexp(y, e);
}

struct Anisotropy
{
  Vec3d centre;
  double m[6]; // the kernel's metric, as CellParticles::m
};

// Sorted particle k's anisotropic kernel, from its neighbours within h (themselves included).
// fullCount: a full neighbourhood's count, 4/3 pi (h / s)^3.
PBF_HD PBF_INLINE Anisotropy anisotropyOf(
  const CellParticles& p, std::uint32_t k, double h, double fullCount)
{
  const Vec3d xi = p.x[k];
  const double h2 = h * h;
  // Sums of w, w r and w r r^T with r = x_j - x_i (relative: no cancellation of positions) and
  // Yu & Turk's weight w = 1 - (|r| / h)^3.
  double weight = 0, second[6] = { 0, 0, 0, 0, 0, 0 };
  Vec3d first{ 0, 0, 0 };
  int count = 0;
  forEachParticleNear(p, xi, [&](std::uint32_t j) {
    const Vec3d r = p.x[j] - xi;
    const double r2 = dot(r, r);
    if (r2 < h2)
    {
      const double q = sqrt(r2) / h;
      const double w = 1.0 - q * q * q;
      weight += w;
      first += r * w;
      second[0] += w * r.x * r.x;
      second[1] += w * r.x * r.y;
      second[2] += w * r.x * r.z;
      second[3] += w * r.y * r.y;
      second[4] += w * r.y * r.z;
      second[5] += w * r.z * r.z;
      ++count;
    }
  });
  Anisotropy a;
  const Vec3d mean = first * (1.0 / weight); // weight >= 1: the particle itself
  a.centre = xi + mean * kCentreBlend;
  for (int i = 0; i < 6; ++i)
  {
    a.m[i] = i == 0 || i == 3 || i == 5 ? 1.0 : 0.0;
  }
  if (static_cast<double>(count) < 0.75 * fullCount)
  {
    return a; // too few neighbours for a shape: the round kernel
  }
  const double c[6] = { second[0] / weight - mean.x * mean.x, second[1] / weight - mean.x * mean.y,
    second[2] / weight - mean.x * mean.z, second[3] / weight - mean.y * mean.y,
    second[4] / weight - mean.y * mean.z, second[5] / weight - mean.z * mean.z };
  double variance[3], axes[9];
  symmetricEigen(c, variance, axes);
  double length[3], longest = 0;
  for (int i = 0; i < 3; ++i)
  {
    length[i] = sqrt(variance[i] > 0 ? variance[i] : 0.0);
    longest = length[i] > longest ? length[i] : longest;
  }
  if (!(longest > 0))
  {
    return a;
  }
  for (int i = 0; i < 3; ++i)
  {
    length[i] = length[i] * kStretchRatio < longest ? longest / kStretchRatio : length[i];
  }
  const double scale = cubeRoot(length[0] * length[1] * length[2]);
  // M = R diag(1 / s^2) R^T with s = length / scale: |A r| for A = R diag(1 / s) R^T.
  double inverse[3];
  for (int i = 0; i < 3; ++i)
  {
    const double s = length[i] / scale;
    inverse[i] = 1.0 / (s * s);
  }
  auto entry = [&](int r, int col) {
    return axes[3 * r] * inverse[0] * axes[3 * col] + axes[3 * r + 1] * inverse[1] * axes[3 * col + 1] +
      axes[3 * r + 2] * inverse[2] * axes[3 * col + 2];
  };
  a.m[0] = entry(0, 0);
  a.m[1] = entry(0, 1);
  a.m[2] = entry(0, 2);
  a.m[3] = entry(1, 1);
  a.m[4] = entry(1, 2);
  a.m[5] = entry(2, 2);
  return a;
}

// Kuhn's six tetrahedra of a cell, as corner bits (x 1, y 2, z 4): 0, a, a | b, 7 for every
// order of the axes. Along each tetrahedron's corners the bits only grow, so of two corners the
// earlier is the edge's lower end; every edge from corner 0 to a corner d is in one of them.
PBF_HD PBF_INLINE int tetrahedronCorner(int t, int c)
{
  constexpr int corners[6][4] = { { 0, 1, 3, 7 }, { 0, 1, 5, 7 }, { 0, 2, 3, 7 },
    { 0, 2, 6, 7 }, { 0, 4, 5, 7 }, { 0, 4, 6, 7 } };
  return corners[t][c];
}

// A vertex of the mesh: the grid edge it lies on (its lower node and direction bits) and where.
struct EdgeVertex
{
  std::int64_t node[3];
  int dir;
  Vec3d position;
};

// The vertex on the edge from corner u to corner v (u's bits a subset of v's) of cell (i, j, k):
// where the linear colour along it crosses iso.
PBF_HD PBF_INLINE EdgeVertex edgeVertex(const NodeGrid& g, std::int64_t i, std::int64_t j,
  std::int64_t k, int u, int v, const double* corner, double iso)
{
  EdgeVertex e;
  e.node[0] = i + (u & 1);
  e.node[1] = j + ((u >> 1) & 1);
  e.node[2] = k + (u >> 2);
  e.dir = v & ~u;
  const Vec3d a = g.at(e.node[0], e.node[1], e.node[2]);
  const Vec3d b = g.at(i + (v & 1), j + ((v >> 1) & 1), k + (v >> 2));
  const double t = (iso - corner[u]) / (corner[v] - corner[u]);
  e.position = a + (b - a) * t;
  return e;
}

// The edges from corner 0 of a cell whose ends lie on the two sides of iso, as bits d (1..7):
// the vertices this cell owns.
PBF_HD PBF_INLINE unsigned ownedCrossings(const double* corner, double iso)
{
  unsigned bits = 0;
  const bool in0 = corner[0] > iso;
  for (int d = 1; d < 8; ++d)
  {
    bits |= (corner[d] > iso) != in0 ? 1u << d : 0u;
  }
  return bits;
}

// Cuts cell (i, j, k), whose corner values (corner c at bits c) lie on both sides of iso, into
// triangles: emit(a, b, c) with EdgeVertex a, b, c counter-clockwise seen from outside.
template <class Emit>
PBF_HD PBF_INLINE void triangulateCell(const NodeGrid& g, std::int64_t i, std::int64_t j,
  std::int64_t k, const double* corner, double iso, Emit&& emit)
{
  for (int t = 0; t < 6; ++t)
  {
    int tet[4];
    int in[4], outside[4], nin = 0, nout = 0;
    for (int c = 0; c < 4; ++c)
    {
      tet[c] = tetrahedronCorner(t, c);
      if (corner[tet[c]] > iso)
      {
        in[nin++] = c;
      }
      else
      {
        outside[nout++] = c;
      }
    }
    if (nin == 0 || nout == 0)
    {
      continue;
    }
    // From the inside corners' centre to the outside ones': the way the normal must face.
    auto centre = [&](const int* list, int count) {
      Vec3d sum{ 0, 0, 0 };
      for (int q = 0; q < count; ++q)
      {
        const int b = tet[list[q]];
        sum += g.at(i + (b & 1), j + ((b >> 1) & 1), k + (b >> 2));
      }
      return sum * (1.0 / count);
    };
    const Vec3d outward = centre(outside, nout) - centre(in, nin);
    // The edge between tetrahedron corners p and q, lower bits first.
    auto edge = [&](int p, int q) {
      const int a = p < q ? p : q, b = p < q ? q : p; // corner order is bit order here
      return edgeVertex(g, i, j, k, tet[a], tet[b], corner, iso);
    };
    auto triangle = [&](const EdgeVertex& a, const EdgeVertex& b, const EdgeVertex& c) {
      const Vec3d n = cross(b.position - a.position, c.position - a.position);
      if (dot(n, outward) < 0)
      {
        emit(a, c, b);
      }
      else
      {
        emit(a, b, c);
      }
    };
    if (nin == 1 || nout == 1)
    {
      const int lone = nin == 1 ? in[0] : outside[0];
      const int* others = nin == 1 ? outside : in;
      triangle(edge(lone, others[0]), edge(lone, others[1]), edge(lone, others[2]));
    }
    else
    {
      // Two in, two out: the quad through the four crossing edges, in cyclic order.
      const EdgeVertex ac = edge(in[0], outside[0]), ad = edge(in[0], outside[1]);
      const EdgeVertex bd = edge(in[1], outside[1]), bc = edge(in[1], outside[0]);
      triangle(ac, ad, bd);
      triangle(ac, bd, bc);
    }
  }
}

// How many triangles triangulateCell emits for these corners (without placing them).
PBF_HD PBF_INLINE int cellTriangleCount(const double* corner, double iso)
{
  int count = 0;
  for (int t = 0; t < 6; ++t)
  {
    int nin = 0;
    for (int c = 0; c < 4; ++c)
    {
      nin += corner[tetrahedronCorner(t, c)] > iso ? 1 : 0;
    }
    count += nin == 0 || nin == 4 ? 0 : (nin == 2 ? 2 : 1);
  }
  return count;
}

// The particles' fields at a vertex q: the colour's gradient (the normal is minus it, unit) and
// the Shepard-normalised poly6 averages of velocity and density. velocityOf(j) and densityOf(j)
// give sorted particle j's; hasVelocity / hasDensity say whether to ask.
struct VertexFields
{
  Vec3<float> normal;
  Vec3<float> velocity;
  float density;
};

// On a cap (where a solid's term is the clipped colour's least), the normal is the solid's inward
// one: the fluid's outward normal there.
template <class VelocityOf, class DensityOf>
PBF_HD PBF_INLINE VertexFields vertexFields(const CellParticles& p, const Kernels<double>& kernels,
  const Vec3d& q, bool hasVelocity, bool hasDensity, VelocityOf&& velocityOf, DensityOf&& densityOf,
  double volume, const DistanceGridView<double>* solids, int solidCount, double iso, double inverseCell)
{
  double weight = 0, density = 0;
  Vec3d gradient{ 0, 0, 0 }, velocity{ 0, 0, 0 };
  forEachParticleNear(p, q, [&](std::uint32_t j) {
    const Vec3d r = q - p.x[j];
    Vec3d mr = r; // the gradient's direction: M r (r for the isotropic kernel)
    const double r2 = p.m ? metricSquare(p.m + 6 * static_cast<std::size_t>(j), r, mr) : dot(r, r);
    if (r2 < kernels.h2)
    {
      const double w = kernels.poly6Within(r2);
      const double d = kernels.h2 - r2;
      gradient += mr * (-6.0 * kernels.poly6Scale * d * d);
      weight += w;
      if (hasVelocity)
      {
        velocity += velocityOf(j) * w;
      }
      if (hasDensity)
      {
        density += densityOf(j) * w;
      }
    }
  });
  double least = volume * weight;
  for (int s = 0; s < solidCount; ++s)
  {
    Vec3d wallGradient;
    const double wall = iso + solids[s].at(q, &wallGradient) * inverseCell;
    if (wall < least)
    {
      least = wall;
      gradient = wallGradient; // d grows out of the solid, into the fluid, as the colour does
    }
  }
  const double g = length(gradient);
  VertexFields out;
  out.normal = g > 0 ? Vec3<float>::from(gradient * (-1.0 / g)) : Vec3<float>{ 0, 0, 0 };
  out.velocity = Vec3<float>::from(weight > 0 ? velocity * (1.0 / weight) : velocity);
  out.density = static_cast<float>(weight > 0 ? density / weight : 0.0);
  return out;
}

// One Laplacian smoothing pass at a vertex: halfway to the mean of its neighbours (the sum taken
// in the order of the neighbours' indices).
template <class NeighbourAt>
PBF_HD PBF_INLINE Vec3d smoothedPosition(const Vec3d& position, int neighbours, NeighbourAt&& at)
{
  if (neighbours == 0)
  {
    return position;
  }
  Vec3d sum{ 0, 0, 0 };
  for (int e = 0; e < neighbours; ++e)
  {
    sum += at(e);
  }
  return position + (sum * (1.0 / neighbours) - position) * 0.5;
}

} // namespace surface
} // namespace pbf
