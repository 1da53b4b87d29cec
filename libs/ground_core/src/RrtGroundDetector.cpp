#include "gam/core/RrtGroundDetector.h"

#include <Eigen/Dense>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace gam
{
Eigen::Vector2d combinedPatchGradient(
	const Eigen::Vector2d& nodesGradient, double residualVariance, const Eigen::Matrix2d& spread,
	const std::vector<Eigen::Vector2d>& localGradients)
{
	const double n = double(localGradients.size());
	if (n < 1) return nodesGradient;
	const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(spread);
	Eigen::Vector2d g = Eigen::Vector2d::Zero();
	for (int axis = 0; axis < 2; axis++)
	{
		const Eigen::Vector2d e = es.eigenvectors().col(axis);
		double sum = 0, sum2 = 0;
		for (const Eigen::Vector2d& lg : localGradients)
		{
			const double v = lg.dot(e);
			sum += v;
			sum2 += v * v;
		}
		const double local = sum / n, nodes = nodesGradient.dot(e);
		// Variance of the mean of the local slopes (sample variance / n) and
		// of the centres' least-squares slope along e.
		const double varLocal = n > 1 ? std::max(0.0, sum2 / n - local * local) / (n - 1.0) : 0.0;
		const double lambda = es.eigenvalues()(axis);
		const bool nodesKnown = lambda > 0 && std::isfinite(residualVariance);
		const double varNodes = nodesKnown ? residualVariance / (n * lambda) : 0.0;
		double along;
		if (!nodesKnown || !(varLocal > 0))
			along = local;  // no spread along e (a line of nodes), or local slopes that agree exactly
		else if (!(varNodes > 0))
			along = nodes;  // centres exactly on their plane
		else
			along = (local / varLocal + nodes / varNodes) / (1.0 / varLocal + 1.0 / varNodes);
		g += along * e;
	}
	return g;
}

void RrtGpdParams::validate() const
{
	checkParamRanges(*this, "");
	// A plane needs a 2D neighbourhood: 1 x N cells are collinear.
	requireParams(neighbourhood_x % 2 == 1 && neighbourhood_y % 2 == 1, "", "s_x and s_y must be odd");
	requireParams(
		min_valid_cells <= neighbourhood_x * neighbourhood_y, "",
		"min_valid_cells=" + std::to_string(min_valid_cells) + " is more than the s_x*s_y cells of a fit");
}

const char* GroundDetection::statusName(Status s)
{
	switch (s)
	{
		case Status::Ok: return "ok";
		case Status::EmptyGrid: return "empty_grid";
		case Status::NoValidSeed: return "no_valid_seed";
		case Status::TooFewNodes: return "too_few_nodes";
		case Status::NoConsensus: return "no_consensus";
	}
	return "unknown";
}

std::string GroundDetection::describe() const
{
	std::ostringstream s;
	s << statusName(status) << ": " << nodes.size() << " nodes, " << planes.size() << " plane(s)";
	if (!planes.empty())
	{
		const Plane& p = planes.front();
		s << "; ground " << p.a << "x + " << p.b << "y + " << p.c << "z + " << p.d << " = 0 (tilt "
		  << p.tiltAngle() * 180.0 / M_PI << " deg)";
		if (ground_from_mount)
			s << ", the robot's floor: the tree's plane " << tree_plane.a << "x + " << tree_plane.b << "y + "
			  << tree_plane.c << "z + " << tree_plane.d << " = 0 was too far from it";
	}
	return s.str();
}

bool RrtGroundDetector::cellHeight(const ElevationGrid& grid, int cx, int cy, float& z) const
{
	const ElevationCell& c = grid.cell(cx, cy);
	if (c.count)
	{
		// (A default-only guard: the paper takes every cell the 3-sigma rule left.)
		if (!paper() && c.variance() > float(m_params.max_cell_std * m_params.max_cell_std)) return false;
		z = c.mean();
		return true;
	}
	z = c.z_idw;
	return !std::isnan(z);
}

bool RrtGroundDetector::fitLocalPlane(const ElevationGrid& grid, int cx, int cy, Plane& plane, double& rms) const
{
	const GridGeometry& g = grid.geometry();
	const int hx = m_params.neighbourhood_x / 2, hy = m_params.neighbourhood_y / 2;
	m_fitPts.clear();
	for (int y = cy - hy; y <= cy + hy; y++)
		for (int x = cx - hx; x <= cx + hx; x++)
		{
			float z;
			if (!g.inside(x, y) || !cellHeight(grid, x, y, z)) continue;
			// Coordinates relative to the centre cell keep the fit well conditioned.
			m_fitPts.emplace_back((x - cx) * g.resolution, (y - cy) * g.resolution, double(z));
		}
	// The paper's local plane needs 3 non-collinear points (the fit refuses
	// collinear ones); the default asks for min_valid_cells.
	if (int(m_fitPts.size()) < (paper() ? 3 : m_params.min_valid_cells)) return false;
	const auto p = fitHeightPlaneLeastSquares(m_fitPts, &rms);
	if (!p) return false;
	// Move the plane from centre-relative to grid coordinates.
	plane = Plane::fromNormalAndPoint(p->normal(), Eigen::Vector3d(g.cx(cx), g.cy(cy), p->heightAt(0, 0)));
	return true;
}

bool RrtGroundDetector::planarEnough(const Plane& local) const
{
	// The paper's seed is "a valid ground cell": its local plane within N_th
	// of the vertical. (A limit on the fit's RMS, 2.5 cm, changed no map of
	// the 27 scenes with any camera and was retired, issue #27: max_cell_std
	// and E_th keep rough and stepped windows out before it could.)
	return local.horizontalNormal() <= m_params.normal_threshold;
}

bool RrtGroundDetector::childAt(
	const ElevationGrid& grid, const GroundNode& parent, int parentIdx, int cx, int cy, GroundNode& child) const
{
	const GridGeometry& g = grid.geometry();
	float z;
	if (!cellHeight(grid, cx, cy, z)) return false;
	const double px = g.cx(cx), py = g.cy(cy);
	// Elevation test against the parent's local plane (lets the tree climb
	// gentle ramps, stops it at steps, boxes and drops).
	if (std::abs(double(z) - parent.local.heightAt(px, py)) > m_params.elevation_threshold) return false;
	Plane pl;
	double rms;
	if (!fitLocalPlane(grid, cx, cy, pl, rms) || !planarEnough(pl)) return false;
	child = GroundNode::fromFit(px, py, pl, rms, parentIdx);
	return true;
}

bool RrtGroundDetector::findSeed(const ElevationGrid& grid, const GroundSeedHint& hint, GroundNode& seed)
{
	const GridGeometry& g = grid.geometry();
	// No seed can lie farther than the grid reaches: cap the offset table.
	const int R =
		std::max(1, int(std::min<double>(std::ceil(m_params.seed_search_radius / g.resolution), std::max(g.nx, g.ny))));
	if (R != m_ringRadius)
	{
		// Cell offsets within the radius, nearest first.
		m_ringOffsets.clear();
		for (int dy = -R; dy <= R; dy++)
			for (int dx = -R; dx <= R; dx++)
				if (dx * dx + dy * dy <= R * R) m_ringOffsets.emplace_back(dx, dy);
		std::stable_sort(m_ringOffsets.begin(), m_ringOffsets.end(), [](const auto& a, const auto& b) {
			return a.first * a.first + a.second * a.second < b.first * b.first + b.second * b.second;
		});
		m_ringRadius = R;
	}
	const int rx = g.ix(hint.x), ry = g.iy(hint.y);
	for (const auto& [dx, dy] : m_ringOffsets)
	{
		const int cx = rx + dx, cy = ry + dy;
		if (!g.inside(cx, cy)) continue;
		const ElevationCell& c = grid.cell(cx, cy);
		if (!c.count) continue;  // the seed must be a real observation
		if (!m_seedExcluded.empty() && m_seedExcluded[g.index(cx, cy)]) continue;
		float z;
		if (!cellHeight(grid, cx, cy, z)) continue;
		// (Default only: the paper has no expected floor height for the seed.)
		if (!paper() && std::abs(z - hint.floor_z) > m_params.seed_height_tolerance) continue;
		Plane pl;
		double rms;
		if (!fitLocalPlane(grid, cx, cy, pl, rms) || !planarEnough(pl)) continue;
		seed = GroundNode::fromFit(g.cx(cx), g.cy(cy), pl, rms, -1);
		return true;
	}
	return false;
}

void RrtGroundDetector::detect(const ElevationGrid& grid, const GroundSeedHint& hint, GroundDetection& out)
{
	out.clear();
	if (grid.observedCount() == 0)
	{
		out.status = GroundDetection::Status::EmptyGrid;
		return;
	}
	const GridGeometry& g = grid.geometry();
	m_resolution = g.resolution;
	m_hint = hint;
	m_rng.seed(m_params.random_seed);
	reserveScratch(g);

	m_seedExcluded.clear();
	// Excludes the cells within d_n of these nodes from the next seed search.
	auto excludeAround = [&](auto&& take) {
		if (m_seedExcluded.empty()) m_seedExcluded.assign(g.cellCount(), 0);
		const int r = int(std::ceil(m_params.expansion_distance / g.resolution));
		for (const GroundNode& n : out.nodes)
		{
			if (!take(n)) continue;
			const int nx_ = g.ix(n.x), ny_ = g.iy(n.y);
			for (int y = std::max(0, ny_ - r); y <= std::min(g.ny - 1, ny_ + r); y++)
				for (int x = std::max(0, nx_ - r); x <= std::min(g.nx - 1, nx_ + r); x++)
					m_seedExcluded[g.index(x, y)] = 1;
		}
	};
	// The paper grows one tree from one seed, and RANSAC needs 3 nodes; the
	// default re-seeds a tree that stayed below min_nodes (a box top), or
	// whose ground plane (the seed's) holds fewer than min_nodes of its
	// nodes or less than half of them: the tree may have started on a flat
	// patch and stepped down from it to the floor (a 3.4 cm cable protector
	// across the bottom of an Astra's image: the ground plane was its top
	// tilted down to the floor, 3 tree nodes, and the floor beyond an extra
	// patch; in another draw of the tree, min_nodes or more, but less than
	// half of the tree: 5.6 % of a held-out scene's floor occupied). A tree from
	// another seed replaces that one only if its ground plane holds as many
	// (`enough`) and passes nearer the floor the robot stands on, at the
	// robot: else the robot may stand at the foot of a ramp whose floor
	// shows few nodes, and the first tree (that floor) is grown again.
	const int attempts = paper() ? 1 : m_params.seed_attempts;
	// The trees are compared by their own ground planes; the robot's floor
	// judges only the tree kept (see groundFromSeed).
	m_judgeAgainstFloor = false;
	bool fitted = false;
	bool haveFirst = false;  // a tree whose ground plane held too few nodes
	GroundNode firstSeed;
	double firstOffset = 0;
	auto offsetAtRobot = [&]() {
		return out.planes.empty() ? std::numeric_limits<double>::infinity()
								  : std::abs(out.planes.front().heightAt(hint.x, hint.y) - hint.floor_z);
	};
	for (int attempt = 0; attempt < attempts; attempt++)
	{
		GroundNode seed;
		if (!findSeed(grid, hint, seed))
		{
			if (attempt == 0)
			{
				out.status = GroundDetection::Status::NoValidSeed;
				return;
			}
			break;
		}
		if (!haveFirst) m_rngAtFirst = m_rng;
		if (m_params.variant == MethodVariant::Paper)
			growTreePaper(grid, seed, out);
		else
			growTree(grid, seed, out);
		if (out.nodes.size() >= minNodes())
		{
			if (paper() || (!haveFirst && attempt + 1 == attempts)) break;
			fitPlanes(out);
			fitted = true;
			const bool enough = !out.planes.empty() &&
								out.plane_support.front() >= std::max<size_t>(minNodes(), (out.nodes.size() + 1) / 2);
			if (enough && (!haveFirst || offsetAtRobot() < firstOffset))
			{
				haveFirst = false;  // this tree stays
				break;
			}
			if (!haveFirst)
			{
				haveFirst = true;
				firstSeed = seed;
				firstOffset = offsetAtRobot();
			}
			// Exclude the seed's plane (or, without one, the seed) and try
			// the next candidate.
			const bool noPlane = out.planes.empty();
			excludeAround([&](const GroundNode& n) { return noPlane ? &n == &out.nodes.front() : n.plane_id == 0; });
			fitted = false;
			continue;
		}
		// The seed was a small flat patch (a box top, a shelf board): exclude
		// the area the tree covered and try the next candidate.
		excludeAround([](const GroundNode&) { return true; });
	}
	if (haveFirst)
	{
		// No other seed gave a better ground: the first tree, grown again
		// from the same random state (the same tree).
		m_rng = m_rngAtFirst;
		growTree(grid, firstSeed, out);
		fitted = false;
	}

	if (out.nodes.size() < minNodes())
	{
		out.status = GroundDetection::Status::TooFewNodes;
		return;
	}
	// The tree kept: its ground plane is judged against the robot's floor
	// from here on, before fill_patches tiles patches off it.
	m_judgeAgainstFloor = m_hint.judge_against_floor && !paper();
	// (The tree's planes, if fitted in the loop, are fitted again only where
	// the floor would replace the seed's plane: the test groundFromSeed runs.)
	if (fitted && m_judgeAgainstFloor && m_seedPlaneFitted)
	{
		m_ransacPts.clear();
		for (const GroundNode& n : out.nodes) m_ransacPts.emplace_back(n.x, n.y, n.z);
		if (floorHoldsMoreNodes(
				m_ransacPts, m_seedPlane, m_hint.floorPlane(), m_params.ransac_inlier_distance, kFloorTestSigmas))
			fitted = false;
	}
	if (!fitted) fitPlanes(out);
	if (m_params.variant != MethodVariant::Paper && m_params.fill_patches && !out.planes.empty())
	{
		const Plane ground = out.planes.front();
		const size_t treeNodes = out.nodes.size();
		fillPatches(grid, ground, out);
		out.fill_nodes = out.nodes.size() - treeNodes;
		if (out.fill_nodes)
		{
			// Fit again with the filled patches (the ground plane holds the seed either way).
			fitPlanes(out);
		}
	}
	out.status = out.planes.empty() ? GroundDetection::Status::NoConsensus : GroundDetection::Status::Ok;
}

void RrtGroundDetector::fillPatches(const ElevationGrid& grid, const Plane& ground, GroundDetection& out)
{
	// Breadth-first from every node off the ground plane (a ramp or a landing
	// the tree reached): candidates s_x (along x) and s_y (along y) cells away
	// in the 8 directions, so that neighbouring nodes' fit windows tile the
	// surface without overlapping; a candidate whose window already holds a
	// node is skipped. A new node passes the tree's tests against its parent
	// (E_th, N_th); it is expanded in turn only while it is off
	// the ground plane or tilted away from it (offGround), so the filling
	// stops where the patch meets the floor again. At most K nodes more than
	// the tree has (2K + 1 in all: the capacity reserved). The budget was K + 1
	// in all: a wide camera (a D435's 87 deg) fills the tree's K + 1 with floor
	// nodes and left none for the ramp (ramp_8deg_0.7m seen by a D435: 10 %
	// of its known cells free; 81 % with a budget of its own).
	const GridGeometry& g = grid.geometry();
	const size_t cap = std::min(maxTreeNodes(g), out.nodes.size() + size_t(m_params.iterations));
	const int sx = m_params.neighbourhood_x, sy = m_params.neighbourhood_y, hx = sx / 2, hy = sy / 2;
	const double off = m_params.ransac_inlier_distance;
	// A node grows the patch if it is off the ground plane, or if its local
	// plane leaves the ground plane by more than that within d_n (the foot of
	// a ramp, still on the floor, tilted with the ramp: often the only node
	// the tree put on a ramp seen from afar). Floor nodes whose local fit is
	// tilted by noise add a few nodes on the floor, which stop there.
	const double reach = m_params.expansion_distance;
	const Eigen::Vector3d gn = ground.normal();
	auto offGround = [&](const GroundNode& n) {
		if (std::abs(ground.signedDistance(n.x, n.y, n.z)) > off) return true;
		// Height of the local plane over the ground plane, d_n away along the
		// local plane's steepest direction relative to the ground's.
		const Eigen::Vector3d ln = n.local.normal();
		const double s = ln.cross(gn).norm();  // sin of the angle between the planes
		return reach * s / std::max(1e-9, std::sqrt(std::max(0.0, 1.0 - s * s))) > off;
	};
	auto windowFree = [&](int cx, int cy) {
		for (int y = std::max(0, cy - hy); y <= std::min(g.ny - 1, cy + hy); y++)
			for (int x = std::max(0, cx - hx); x <= std::min(g.nx - 1, cx + hx); x++)
				if (m_hasNode[g.index(x, y)]) return false;
		return true;
	};
	static constexpr int kDirs[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {1, 1}, {1, -1}, {-1, 1}, {-1, -1}};
	// Only within the range the map takes evidence from: a wide, noisy camera
	// (a D435) has many floor nodes tilted by noise beyond it, which would use
	// up the budget before the ramp ahead is tiled.
	m_fillQueue.clear();
	for (uint32_t i = 0; i < out.nodes.size(); i++)
		if (m_hint.withinFillRange(out.nodes[i].x, out.nodes[i].y) && offGround(out.nodes[i])) m_fillQueue.push_back(i);
	for (size_t q = 0; q < m_fillQueue.size() && out.nodes.size() < cap; q++)
	{
		const uint32_t pi = m_fillQueue[q];
		const GroundNode parent = out.nodes[pi];  // a copy: addTreeNode() appends to out.nodes
		const int pcx = g.ix(parent.x), pcy = g.iy(parent.y);
		for (const auto& d : kDirs)
		{
			if (out.nodes.size() >= cap) break;
			const int cx = pcx + d[0] * sx, cy = pcy + d[1] * sy;
			if (!g.inside(cx, cy) || !m_hint.withinFillRange(g.cx(cx), g.cy(cy)) || !windowFree(cx, cy)) continue;
			GroundNode node;
			if (!childAt(grid, parent, int(pi), cx, cy, node)) continue;
			addTreeNode(g, node, cx, cy, out);
			if (offGround(node)) m_fillQueue.push_back(uint32_t(out.nodes.size() - 1));
		}
	}
}

size_t RrtGroundDetector::maxTreeNodes(const GridGeometry& g) const
{
	// The tree's K + 1 and fill_patches' K more.
	return std::min(2 * size_t(m_params.iterations) + 1, g.cellCount());
}

void RrtGroundDetector::reserveScratch(const GridGeometry& g)
{
	// Everything detect() fills is bounded by the most nodes a tree can have
	// (2K + 1 with fill_patches, and one per cell), s_x * s_y fit cells and max_planes: reserving
	// that once keeps every later frame (with the same grid and parameters)
	// free of heap allocations. No-ops when the capacity is already there.
	const size_t maxNodes = maxTreeNodes(g);
	m_nodeCells.reserve(maxNodes);
	m_nodeX.reserve(maxNodes);
	m_nodeY.reserve(maxNodes);
	m_remaining.reserve(maxNodes);
	m_rest.reserve(maxNodes);
	m_flag.reserve(maxNodes);
	m_ransacPts.reserve(maxNodes);
	m_ransacInliers.reserve(maxNodes);
	m_ransac.inliers.reserve(maxNodes);
	m_fitPts.reserve(size_t(m_params.neighbourhood_x) * size_t(m_params.neighbourhood_y));
	m_candidates.reserve(maxNodes);
	m_fillQueue.reserve(maxNodes);
	m_absDist.reserve(maxNodes);
	m_localGradients.reserve(maxNodes);
	m_cluster.reserve(maxNodes);
	m_bfs.reserve(maxNodes);
	m_patchNodes.reserve(maxNodes);
	m_deferred.reserve(size_t(2 * std::max(1, m_params.max_planes)));
	if (m_hasNode.size() != g.cellCount())
	{
		m_hasNode.assign(g.cellCount(), 0);
		m_nodeCells.clear();  // indices into the old grid (it may have been larger)
	}
}

void RrtGroundDetector::nodeIndexReset()
{
	m_nodeX.clear();
	m_nodeY.clear();
}

void RrtGroundDetector::nodeIndexAdd(const GroundNode& node)
{
	m_nodeX.push_back(node.x);
	m_nodeY.push_back(node.y);
}

uint32_t nearestPoint(const float* xs, const float* ys, size_t n, float qx, float qy, float& bestD2)
{
	bestD2 = std::numeric_limits<float>::max();
	int32_t best = -1;
	size_t i = 0;
#if defined(__SSE2__)
	if (n >= 4)
	{
		// Four lanes, lane j testing nodes j, j + 4, ...: a strict < keeps
		// each lane's lowest index on a tie, and the lanes are merged below
		// by distance, then index.
		const __m128 QX = _mm_set1_ps(qx), QY = _mm_set1_ps(qy);
		__m128 laneD2 = _mm_set1_ps(bestD2);
		__m128i laneIdx = _mm_set1_epi32(-1), idx = _mm_setr_epi32(0, 1, 2, 3);
		const __m128i four = _mm_set1_epi32(4);
		for (; i + 4 <= n; i += 4)
		{
			const __m128 dx = _mm_sub_ps(QX, _mm_loadu_ps(xs + i)), dy = _mm_sub_ps(QY, _mm_loadu_ps(ys + i));
			const __m128 d2 = _mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy));
			const __m128 closer = _mm_cmplt_ps(d2, laneD2);
			laneD2 = _mm_or_ps(_mm_and_ps(closer, d2), _mm_andnot_ps(closer, laneD2));
			const __m128i c = _mm_castps_si128(closer);
			laneIdx = _mm_or_si128(_mm_and_si128(c, idx), _mm_andnot_si128(c, laneIdx));
			idx = _mm_add_epi32(idx, four);
		}
		alignas(16) float d[4];
		alignas(16) int32_t k[4];
		_mm_store_ps(d, laneD2);
		_mm_store_si128(reinterpret_cast<__m128i*>(k), laneIdx);
		for (int j = 0; j < 4; j++)
			if (k[j] >= 0 && (d[j] < bestD2 || (d[j] == bestD2 && k[j] < best)))
			{
				bestD2 = d[j];
				best = k[j];
			}
	}
#endif
	for (; i < n; i++)
	{
		float d2 = 0;
		const float dx = qx - xs[i];
		d2 += dx * dx;
		const float dy = qy - ys[i];
		d2 += dy * dy;
		if (d2 < bestD2 || (d2 == bestD2 && int32_t(i) < best))
		{
			bestD2 = d2;
			best = int32_t(i);
		}
	}
	return uint32_t(best);
}

uint32_t RrtGroundDetector::nodeIndexNearest(float qx, float qy, float& bestD2) const
{
	// Every node tested: a tree has at most 2K + 1 nodes (1201 with the
	// defaults), and four centres a step from two flat arrays cost less than
	// the bucket grid's ring search this replaced, whose queries (the random
	// points of the search window) are mostly far from every node and
	// visited many empty buckets (2026-11-29: 5 % of a Kinect One frame's
	// profile, RRT-GPD stage 21 % shorter; doc/speed-and-memory.md).
	return nearestPoint(m_nodeX.data(), m_nodeY.data(), m_nodeX.size(), qx, qy, bestD2);
}

void RrtGroundDetector::addTreeNode(const GridGeometry& g, const GroundNode& node, int cx, int cy, GroundDetection& out)
{
	const uint32_t c = uint32_t(g.index(cx, cy));
	m_hasNode[c] = 1;
	m_nodeCells.push_back(c);
	out.nodes.push_back(node);
	nodeIndexAdd(node);
}

void RrtGroundDetector::startTree(const GridGeometry& g, const GroundNode& seed, GroundDetection& out)
{
	out.nodes.clear();
	out.iterations = 0;
	for (uint32_t c : m_nodeCells) m_hasNode[c] = 0;
	m_nodeCells.clear();

	// The paper keeps the nodes in a k-d tree for the nearest-node queries.
	// nanoflann's dynamic k-d tree did that, but it rebuilds sub-trees as nodes
	// are added and its PooledAllocator mallocs and frees their memory on every
	// rebuild (hundreds of allocations per frame), which a real-time frame loop
	// must not do. The tree is small (at most 2K + 1 nodes): two arrays of
	// its centres, reused between frames, give the same exact nearest
	// neighbour (see nodeIndexNearest).
	nodeIndexReset();
	out.nodes.reserve(maxTreeNodes(g));
	addTreeNode(g, seed, g.ix(seed.x), g.iy(seed.y), out);
}

void RrtGroundDetector::growTree(const ElevationGrid& grid, const GroundNode& seed, GroundDetection& out)
{
	const GridGeometry& g = grid.geometry();
	startTree(g, seed, out);

	// Sampling window: the nodes' bounding box grown by window_margin, clamped
	// to the grid. It grows and drifts as the tree explores.
	const double margin = m_params.window_margin;
	double bx0 = seed.x, bx1 = seed.x, by0 = seed.y, by1 = seed.y;
	std::uniform_real_distribution<double> U(0.0, 1.0);
	const double dn = m_params.expansion_distance;

	for (int k = 0; k < m_params.iterations; k++)
	{
		out.iterations = k + 1;
		const double wx0 = std::max(g.x_min, bx0 - margin), wx1 = std::min(g.x_max(), bx1 + margin);
		const double wy0 = std::max(g.y_min, by0 - margin), wy1 = std::min(g.y_max(), by1 + margin);
		const double qx = wx0 + U(m_rng) * (wx1 - wx0), qy = wy0 + U(m_rng) * (wy1 - wy0);

		float nearD2 = 0;
		const uint32_t nearIdx = nodeIndexNearest(float(qx), float(qy), nearD2);
		const GroundNode near = out.nodes[nearIdx];  // copy: push_back may reallocate

		const double dist = std::sqrt(double(nearD2));
		if (dist < 1e-9) continue;
		const double s = std::min(1.0, dn / dist);
		const double nx_ = near.x + (qx - near.x) * s, ny_ = near.y + (qy - near.y) * s;
		const int cx = g.ix(nx_), cy = g.iy(ny_);
		if (!g.inside(cx, cy)) continue;
		if (m_hasNode[g.index(cx, cy)]) continue;
		GroundNode node;
		if (!childAt(grid, near, int(nearIdx), cx, cy, node)) continue;
		addTreeNode(g, node, cx, cy, out);
		bx0 = std::min(bx0, g.cx(cx));
		bx1 = std::max(bx1, g.cx(cx));
		by0 = std::min(by0, g.cy(cy));
		by1 = std::max(by1, g.cy(cy));
	}
}

bool RrtGroundDetector::paperElevationOk(const GroundNode& near, double px, double py, const Plane& pl) const
{
	// Line 14 as printed: the new local plane's height at the new node against
	// x_near's height (not x_near's plane extrapolated to the new node, the
	// reading until issue #30: on a slope of more than E_th / d_n = 7 deg the
	// printed test stops the tree).
	return std::abs(pl.heightAt(px, py) - double(near.z)) <= m_params.elevation_threshold;
}

bool RrtGroundDetector::paperNormalOk(const GroundNode& node, const Plane& pl) const
{
	// N_th: the paper compares the new local normal with the parent's. As
	// printed (n_new . n_near <= N_th) it would accept only normals nearly
	// perpendicular to the parent's; we read it as the sine of the angle
	// between them, |n_new x n_near| <= N_th (0.2 = 11.5 deg, the same angle
	// the default variant allows against the vertical).
	const Eigen::Vector3d a(pl.a, pl.b, pl.c), b(node.local.a, node.local.b, node.local.c);
	return a.cross(b).norm() <= m_params.normal_threshold * a.norm() * b.norm();
}

void RrtGroundDetector::growTreePaper(const ElevationGrid& grid, const GroundNode& seed, GroundDetection& out)
{
	// Algorithm 1 as printed (our reading where it is ambiguous, see
	// doc/paper-vs-implementation.md):
	//  - q uniform in a search window centred on the centroid of the explored
	//    nodes (it drifts toward them), half side = the nodes' largest offset
	//    from the centroid along the axis + window_margin;
	//  - x_new = x_near + d_n (q - x_near) / |q - x_near|: always a d_n step;
	//  - x_new is kept only if its local plane's height is within E_th of
	//    x_near's (line 14); it joins as a child of x_near if its normal
	//    passes N_th against x_near's, else (lines 17-22) as a child of the
	//    first other node within d_n of it, nearest first, whose normal it
	//    passes.
	const GridGeometry& g = grid.geometry();
	startTree(g, seed, out);
	PaperSearchWindow window;
	window.add(seed.x, seed.y);
	std::uniform_real_distribution<double> U(0.0, 1.0);
	const double dn = m_params.expansion_distance, margin = m_params.window_margin;
	const float dn2 = float(dn * dn);

	for (int k = 0; k < m_params.iterations; k++)
	{
		out.iterations = k + 1;
		double wx0, wx1, wy0, wy1;
		window.bounds(g, margin, wx0, wx1, wy0, wy1);
		const double qx = wx0 + U(m_rng) * (wx1 - wx0), qy = wy0 + U(m_rng) * (wy1 - wy0);

		float nearD2 = 0;
		const uint32_t nearIdx = nodeIndexNearest(float(qx), float(qy), nearD2);
		const double dist = std::sqrt(double(nearD2));
		if (dist < 1e-9) continue;
		const GroundNode near = out.nodes[nearIdx];
		const double nx_ = near.x + (qx - near.x) * (dn / dist), ny_ = near.y + (qy - near.y) * (dn / dist);
		const int cx = g.ix(nx_), cy = g.iy(ny_);
		if (!g.inside(cx, cy)) continue;
		if (m_hasNode[g.index(cx, cy)]) continue;
		float z;
		if (!cellHeight(grid, cx, cy, z)) continue;
		Plane pl;
		double rms;
		if (!fitLocalPlane(grid, cx, cy, pl, rms)) continue;
		const double px = g.cx(cx), py = g.cy(cy);
		// Line 14: the elevation test against x_near decides whether x_new is
		// ground at all; line 15: the normal test against x_near; lines 17-22
		// (only when the normal test failed): the other nodes within d_n of
		// x_new, nearest first, by the normal test.
		if (!paperElevationOk(near, px, py, pl)) continue;
		int parent = -1;
		if (paperNormalOk(near, pl))
			parent = int(nearIdx);
		else
		{
			m_candidates.clear();
			for (uint32_t i = 0; i < out.nodes.size(); i++)
			{
				if (i == nearIdx) continue;
				const float ex = float(px) - out.nodes[i].x, ey = float(py) - out.nodes[i].y;
				const float d2 = ex * ex + ey * ey;
				if (d2 <= dn2) m_candidates.emplace_back(d2, i);
			}
			std::sort(m_candidates.begin(), m_candidates.end());
			for (const auto& [d2, i] : m_candidates)
				if (paperNormalOk(out.nodes[i], pl))
				{
					parent = int(i);
					break;
				}
		}
		if (parent < 0) continue;
		addTreeNode(g, GroundNode::fromFit(px, py, pl, rms, parent), cx, cy, out);
		window.add(px, py);
	}
}

bool RrtGroundDetector::groundFromSeed(
	GroundDetection& out, const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp)
{
	// pts are the nodes in order: pts[0] is the seed. The nodes' noise about
	// the seed's local plane (sigma = 1.4826 x the median absolute distance
	// of those within the inlier distance) sets a tight band, 3 sigma + the
	// cell quantisation (see noiseBand); the plane is refitted (total least
	// squares) to the nodes inside that band, which then holds the nodes the
	// better plane brings in, until the set stops changing. Refitting to all
	// nodes within the 2.5 cm instead let the foot of a wide ramp (its first
	// 25 cm at 6 deg) tilt the floor toward it, which took in more of it.
	out.ground_from_mount = false;
	m_seedPlaneFitted = false;
	Plane pl = out.nodes.front().local;
	m_absDist.clear();
	for (const Eigen::Vector3d& q : pts)
	{
		const double d = std::abs(pl.signedDistance(q.x(), q.y(), q.z()));
		if (d <= rp.inlier_distance) m_absDist.push_back(d);
	}
	if (m_absDist.size() < 3) return false;
	const double band = noiseBand(rp.inlier_distance);
	size_t last = 0;
	for (int it = 0; it < 20; it++)
	{
		m_ransacInliers.clear();
		for (const Eigen::Vector3d& q : pts)
			if (std::abs(pl.signedDistance(q.x(), q.y(), q.z())) <= band) m_ransacInliers.push_back(q);
		if (m_ransacInliers.size() == last || m_ransacInliers.size() < 3) break;
		last = m_ransacInliers.size();
		const auto refined = fitPlaneTotalLeastSquares(m_ransacInliers);
		if (!refined || refined->horizontalNormal() > rp.max_horizontal_normal) break;
		pl = *refined;
	}
	// Its nodes: all within the inlier distance, as for any plane.
	const auto takeNodesOf = [&](const Plane& plane) {
		m_ransac.plane = plane;
		m_ransac.inliers.clear();
		for (size_t i = 0; i < pts.size(); i++)
			if (std::abs(plane.signedDistance(pts[i].x(), pts[i].y(), pts[i].z())) <= rp.inlier_distance)
				m_ransac.inliers.push_back(i);
		return m_ransac.inliers.size() >= std::max<size_t>(3, rp.min_inliers);
	};
	if (!takeNodesOf(pl)) return false;
	m_seedPlane = pl;
	m_seedPlaneFitted = true;
	if (!m_judgeAgainstFloor) return true;
	// A stereo camera's correlated noise can tilt the seed's window as a
	// whole, and the refit then drift onto a plane through the near floor and
	// another level (a step's lower floor that fill_patches tiled, a box
	// top). Such a plane holds fewer of the nodes than the floor the mount
	// predicts (level, at the robot's floor height); where it holds
	// significantly fewer, that floor is the ground, as where the tree's plane
	// passes too far from it under the robot (the pipeline's
	// max_ground_offset), and the patches are fitted around it.
	if (!floorHoldsMoreNodes(pts, pl, m_hint.floorPlane(), rp.inlier_distance, kFloorTestSigmas)) return true;
	out.ground_from_mount = true;
	out.tree_plane = pl;
	// (It holds at least 10 nodes more than the seed's plane: 3 sqrt(n) < n.)
	return takeNodesOf(m_hint.floorPlane());
}

bool floorHoldsMoreNodes(
	const std::vector<Eigen::Vector3d>& nodes, const Plane& plane, const Plane& floor, double inlierDistance, double k)
{
	// McNemar's test on the nodes only one of the two planes holds: under
	// "neither plane is better" each such node is the floor's with chance
	// 1/2, so the difference of the two counts has mean 0 and standard
	// deviation sqrt(their sum).
	size_t floorOnly = 0, planeOnly = 0;
	for (const Eigen::Vector3d& q : nodes)
	{
		const bool onFloor = std::abs(floor.signedDistance(q.x(), q.y(), q.z())) <= inlierDistance;
		const bool onPlane = std::abs(plane.signedDistance(q.x(), q.y(), q.z())) <= inlierDistance;
		floorOnly += onFloor && !onPlane;
		planeOnly += onPlane && !onFloor;
	}
	return double(floorOnly) - double(planeOnly) > k * std::sqrt(double(floorOnly + planeOnly));
}

double RrtGroundDetector::noiseBand(double cap)
{
	// 3 sigma of the distances in m_absDist (sigma = 1.4826 x their median:
	// robust to the few that belong to something else), plus the most a
	// cell's mean can sit off a plane tilted by N_th at the cell centre
	// (d_r / 2 * tan(asin N_th): 5 mm at 5 cm and 11.5 deg); at most `cap`.
	// Reorders m_absDist.
	if (m_absDist.empty()) return cap;
	auto mid = m_absDist.begin() + long(m_absDist.size() / 2);
	std::nth_element(m_absDist.begin(), mid, m_absDist.end());
	const double sigma = 1.4826 * *mid;
	const double nth = std::min(m_params.normal_threshold, 0.999);
	return std::min(cap, 3.0 * sigma + 0.5 * m_resolution * nth / std::sqrt(1.0 - nth * nth));
}

void RrtGroundDetector::keepLargestCluster(const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp)
{
	// A patch is one connected surface: nodes link when they are at most d_n
	// apart (the tree's longest step; filled nodes are s_x cells apart). A
	// plane's consensus can gather distant groups at the same height (the top
	// of a cable protector on one side of the robot and the middle of a ramp
	// on the other: one 4 cm "patch" that freed both).
	std::vector<size_t>& in = m_ransac.inliers;
	const size_t n = in.size();
	const double link2 = m_params.expansion_distance * m_params.expansion_distance;
	m_cluster.assign(n, -1);
	int best = -1, nClusters = 0;
	size_t bestSize = 0;
	for (size_t s0 = 0; s0 < n; s0++)
	{
		if (m_cluster[s0] >= 0) continue;
		const int c = nClusters++;
		m_bfs.clear();
		m_bfs.push_back(s0);
		m_cluster[s0] = c;
		for (size_t h = 0; h < m_bfs.size(); h++)
		{
			const Eigen::Vector3d& a = pts[in[m_bfs[h]]];
			for (size_t j = 0; j < n; j++)
			{
				if (m_cluster[j] >= 0) continue;
				const Eigen::Vector3d& b = pts[in[j]];
				const double dx = a.x() - b.x(), dy = a.y() - b.y();
				if (dx * dx + dy * dy > link2) continue;
				m_cluster[j] = c;
				m_bfs.push_back(j);
			}
		}
		if (m_bfs.size() > bestSize)
		{
			bestSize = m_bfs.size();
			best = c;
		}
	}
	if (nClusters <= 1) return;
	size_t w = 0;
	for (size_t i = 0; i < n; i++)
		if (m_cluster[i] == best) in[w++] = in[i];
	in.resize(w);
	refitToInliers(pts, rp);
}

void RrtGroundDetector::refitToInliers(const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp)
{
	m_ransacInliers.clear();
	for (size_t i : m_ransac.inliers) m_ransacInliers.push_back(pts[i]);
	const auto refined = fitPlaneTotalLeastSquares(m_ransacInliers);
	if (refined && refined->horizontalNormal() <= rp.max_horizontal_normal) m_ransac.plane = *refined;
}

void RrtGroundDetector::dropCreaseNodes(
	const GroundDetection& out, const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp)
{
	// A patch's nodes lie on it and measured its tilt. A node whose own local
	// plane parts from the patch by more than the inlier distance across its
	// fit window, beyond 3 sigma of its own slope, sits on a crease (the end
	// of a landing next to a ramp): its centre is within the band, but it
	// bends the refit toward the surface next to it (the far side of an 8 deg
	// ramp came out at 4.5-5 deg, with the landing's last row of nodes in it).
	// Those nodes leave the patch. The slope's sigma of a least-squares fit
	// over the s_x x s_y cells d_r apart: rms / sqrt(sum (x - mean)^2), the
	// sum = s_y d_r^2 h (h + 1) (2h + 1) / 3 along x for h = (s_x - 1) / 2
	// (6 d_r^2 for 3 x 3); the smaller of the two axes.
	std::vector<size_t>& in = m_ransac.inliers;
	const int sx = m_params.neighbourhood_x, sy = m_params.neighbourhood_y;
	const double window = std::max(sx, sy) * m_resolution;
	auto spreadAlong = [&](int s, int other) {
		const double h = (s - 1) / 2;
		return m_resolution * std::sqrt(double(other) * h * (h + 1) * (2 * h + 1) / 3.0);
	};
	const double spread = std::min(spreadAlong(sx, sy), spreadAlong(sy, sx));
	const Eigen::Vector3d n = m_ransac.plane.normal();
	auto onCrease = [&](size_t i) {
		const GroundNode& node = out.nodes[m_remaining[i]];
		const double maxSine = rp.inlier_distance / window + 3.0 * double(node.fit_rms) / spread;
		return node.local.normal().cross(n).norm() > maxSine;
	};
	// Decide before compacting: a patch left with fewer than 3 nodes keeps
	// them all.
	const size_t kept = size_t(std::count_if(in.begin(), in.end(), [&](size_t i) { return !onCrease(i); }));
	if (kept == in.size() || kept < 3) return;
	in.erase(std::remove_if(in.begin(), in.end(), onCrease), in.end());
	refitToInliers(pts, rp);
}

void RrtGroundDetector::fitPlanes(GroundDetection& out)
{
	// RANSAC over the node centres gives the ground plane; further RANSAC rounds
	// over the remaining nodes give ramps and other ground patches that the tree
	// reached through small elevation changes.
	// (All vectors are members: see reserveScratch.) Any planes of an earlier
	// fit of these nodes (another tree, or before fill_patches) are dropped.
	out.planes.clear();
	out.plane_support.clear();
	out.ground_from_mount = false;
	m_seedPlaneFitted = false;
	for (GroundNode& n : out.nodes) n.plane_id = -1;
	std::vector<size_t>& remaining = m_remaining;
	remaining.resize(out.nodes.size());
	for (size_t i = 0; i < remaining.size(); i++) remaining[i] = i;
	std::vector<Eigen::Vector3d>& pts = m_ransacPts;
	RansacParams rp;
	rp.iterations = m_params.ransac_iterations;
	rp.inlier_distance = m_params.ransac_inlier_distance;
	rp.max_horizontal_normal = m_params.normal_threshold;
	if (paper())
	{
		// The paper's RANSAC: the plane of the largest consensus, as found
		// (no tilt limit on the candidates, no refit to the inliers).
		rp.max_horizontal_normal = 1.0;
		rp.refine = false;
	}
	out.planes.reserve(size_t(m_params.max_planes));
	out.plane_support.reserve(size_t(m_params.max_planes));
	m_patchNodes.clear();
	m_deferred.clear();

	// Keeps the remaining nodes whose m_flag is 0, in order.
	auto keepUnflagged = [&]() {
		m_rest.clear();
		for (size_t i = 0; i < remaining.size(); i++)
			if (!m_flag[i]) m_rest.push_back(remaining[i]);
		remaining.swap(m_rest);
	};

	// The paper fits one plane: the ground.
	const int maxPlanes = m_params.variant == MethodVariant::Paper ? 1 : m_params.max_planes;
	// A round whose consensus is no patch (a line of nodes, scattered nodes)
	// removes those nodes but takes no plane's place; at most 2 x max_planes
	// rounds.
	for (int round = 0; int(out.planes.size()) < maxPlanes && remaining.size() >= 3 && round < 2 * maxPlanes; round++)
	{
		const int k = int(out.planes.size());
		// The ground plane: any 3 nodes, as in the paper (it took min_nodes / 2
		// = 4 until issue #27, which changed no cell of the 27 scenes with any
		// camera model; the tree has min_nodes nodes anyway).
		rp.min_inliers = k == 0 ? 3 : m_params.min_nodes_per_extra_plane;
		if (k > 0 && m_params.min_nodes_per_extra_plane == 0) break;
		pts.clear();
		for (size_t i : remaining) pts.emplace_back(out.nodes[i].x, out.nodes[i].y, out.nodes[i].z);
		// The ground plane is the one the seed (the floor under the robot,
		// node 0) lies on, not the largest consensus (the paper's): a ramp
		// and its landing in view can hold more nodes than the floor (in
		// ramp_6deg the ramp was the ground plane in 2 of 11 frames, and the
		// floor around the robot an obstacle), and so can a plane through the
		// seed tilted onto them. So it grows from the seed's own local plane
		// (groundFromSeed). If that plane lacks the support, the largest
		// consensus.
		bool found = k == 0 && m_params.variant != MethodVariant::Paper && groundFromSeed(out, pts, rp);
		if (!found) found = fitPlaneRansac(pts, rp, m_rng, m_ransac, m_ransacInliers);
		if (!found) break;
		if (k > 0) keepLargestCluster(pts, rp);
		if (k > 0) dropCreaseNodes(out, pts, rp);
		const RansacResult& r = m_ransac;
		if (r.inliers.size() < std::max<size_t>(3, rp.min_inliers))
		{
			// Scattered consensus without a patch of the size: those nodes are no patch.
			m_flag.assign(remaining.size(), 0);
			for (size_t i : r.inliers) m_flag[i] = 1;
			keepUnflagged();
			continue;
		}

		Plane plane = r.plane;
		// Nearly collinear node sets (a corridor crossed by one line of nodes)
		// leave the roll about that line undetermined: the inliers' local
		// normals, which every node measured itself, measure it too. Each axis
		// takes the two measurements weighted by their measured precision
		// (combinedPatchGradient). The mean of the local normals alone, each
		// fitted over one s_x x s_y window that a stereo camera's correlated
		// noise tilts as a whole, put the 8 deg ramp 0.7 m wide of
		// ramp_8deg_0.7m seen by a D435 at 7.1 deg with 0.8 deg of roll in one
		// frame (over 11 frames the local slopes averaged 0.127, the node
		// centres' planes 0.134; true 0.1405), and the cells along its foot
		// 1-2 cm below it: drops.
		Eigen::Vector2d mean2 = Eigen::Vector2d::Zero();
		for (size_t i : r.inliers) mean2 += pts[i].head<2>();
		mean2 /= double(r.inliers.size());
		Eigen::Matrix2d C = Eigen::Matrix2d::Zero();
		for (size_t i : r.inliers)
		{
			const Eigen::Vector2d d = pts[i].head<2>() - mean2;
			C += d * d.transpose();
		}
		C /= double(r.inliers.size());
		const double minorStd =
			std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(C).eigenvalues()(0)));
		// An extra patch must be an area, not a line of nodes along the top of
		// a cable protector or a kerb: those are obstacles, not ground. Area:
		// wider than two local-fit windows side by side (nodes in two
		// adjacent columns of windows have a minor std of half a window,
		// 7.5 cm; a 25 cm cable protector holds two at most). It was d_n / 4
		// (10 cm), which refused the part of a 0.8 m ramp a camera sees from
		// its side (13 nodes, 9.5 cm).
		const double window = std::max(m_params.neighbourhood_x, m_params.neighbourhood_y) * m_resolution;
		const bool lineLike = minorStd <= 0.5 * window;
		// A line that continues an accepted extra patch below its plane is that
		// patch's crest (continuesPatchAtCrest): a ground patch all the same.
		if (k > 0 && lineLike && !(k > 1 && continuesPatchAtCrest(r.plane, out, rp.inlier_distance)))
		{
			m_flag.assign(remaining.size(), 0);
			for (size_t i : r.inliers) m_flag[i] = 1;
			keepUnflagged();
			continue;
		}
		// (Not the robot's floor standing in for the ground plane: that is level.)
		if (!paper() && minorStd < 0.5 * m_params.expansion_distance && !(k == 0 && out.ground_from_mount))
			plane = patchFromNodesAndNormals(out, pts, C);
		if (k == 0)
		{
			// The extra patches' inlier distance, from this frame's noise and
			// the grid: the ground plane's own nodes' noise band about it (see
			// noiseBand; the ramp-foot nodes inside its 2.5 cm do not inflate a
			// median). With the ground plane's 2.5 cm, one plane halfway
			// between a 6 deg ramp and its flat landing held the nodes of both
			// (a 3 deg compromise, up to 2.5 cm off either, which ate the
			// ground band and hid a 4 cm cable on the ramp) and beat either
			// true plane.
			m_absDist.clear();
			for (size_t i : r.inliers)
				if (m_hint.withinFillRange(pts[i].x(), pts[i].y()))
					m_absDist.push_back(std::abs(plane.signedDistance(pts[i].x(), pts[i].y(), pts[i].z())));
			if (m_absDist.size() < 3)
			{
				// Too few near nodes for a median: all of them (each once).
				m_absDist.clear();
				for (size_t i : r.inliers)
					m_absDist.push_back(std::abs(plane.signedDistance(pts[i].x(), pts[i].y(), pts[i].z())));
			}
			rp.inlier_distance = noiseBand(m_params.ransac_inlier_distance);
			out.patch_inlier_distance = rp.inlier_distance;
		}
		if (k > 0)
		{
			// A ground patch joins the ground it is reached from without a
			// step: a ramp meets the floor along its foot, a landing meets its
			// ramp. The flat floor 5 cm below a small downward step is parallel
			// to the floor above and meets it nowhere; the tree crosses that
			// step (E_th is 5 cm, and a node whose window straddles the edge
			// is tilted) and fill_patches tiled the lower level, whose plane
			// then freed it as ground, edge and all (the 5 cm step of the
			// detection-range approach was lost from 3.5 to 3.0 m). A patch
			// that joins no accepted plane yet (a landing whose ramp has not
			// been fitted) waits until one is accepted.
			const size_t begin = m_patchNodes.size();
			for (size_t i : r.inliers) m_patchNodes.push_back(remaining[i]);
			m_flag.assign(remaining.size(), 0);
			for (size_t i : r.inliers) m_flag[i] = 1;
			keepUnflagged();
			if (!joinsAcceptedPlane(plane, begin, m_patchNodes.size(), out, rp.inlier_distance))
			{
				m_deferred.push_back({plane, begin, m_patchNodes.size(), false});
				continue;
			}
			acceptPatch(plane, begin, m_patchNodes.size(), out);
			continue;
		}
		const int id = int(out.planes.size());
		out.planes.push_back(plane);
		out.plane_support.push_back(r.inliers.size());
		m_flag.assign(remaining.size(), 0);
		for (size_t i : r.inliers)
		{
			m_flag[i] = 1;
			out.nodes[remaining[i]].plane_id = id;
		}
		keepUnflagged();
	}
	// Patches set aside: each accepted plane may be the one they join.
	for (bool more = true; more && int(out.planes.size()) < maxPlanes;)
	{
		more = false;
		for (DeferredPatch& dp : m_deferred)
			if (!dp.taken && int(out.planes.size()) < maxPlanes &&
				joinsAcceptedPlane(dp.plane, dp.begin, dp.end, out, rp.inlier_distance))
			{
				dp.taken = true;
				acceptPatch(dp.plane, dp.begin, dp.end, out);
				more = true;
			}
	}
}

Plane RrtGroundDetector::patchFromNodesAndNormals(
	const GroundDetection& out, const std::vector<Eigen::Vector3d>& pts, const Eigen::Matrix2d& spread)
{
	const std::vector<size_t>& in = m_ransac.inliers;
	const double n = double(in.size());
	Eigen::Vector3d c = Eigen::Vector3d::Zero();
	for (size_t i : in) c += pts[i];
	c /= n;
	const Plane& nodesPlane = m_ransac.plane;
	double rss = 0;
	for (size_t i : in)
	{
		const double d = nodesPlane.signedDistance(pts[i].x(), pts[i].y(), pts[i].z());
		rss += d * d;
	}
	auto gradient = [](const Plane& pl) { return Eigen::Vector2d(-pl.a / pl.c, -pl.b / pl.c); };
	m_localGradients.clear();
	for (size_t i : in) m_localGradients.push_back(gradient(out.nodes[m_remaining[i]].local));
	// The residual variance of a fit of 3 parameters.
	const Eigen::Vector2d g =
		combinedPatchGradient(gradient(nodesPlane), rss / std::max(1.0, n - 3.0), spread, m_localGradients);
	return Plane::fromNormalAndPoint(Eigen::Vector3d(-g.x(), -g.y(), 1.0), c);
}

namespace
{
// Whether `plane` and node q's plane Q meet between nodes p and q (a tree
// step apart): plane's height over Q changes sign from p to q, or is within
// `pBand` of it at p, or within `qBand` at q.
bool planesMeetBetween(
	const Plane& plane, const Plane& Q, const GroundNode& p, const GroundNode& q, double pBand, double qBand)
{
	const double atP = plane.heightAt(p.x, p.y) - Q.heightAt(p.x, p.y);
	const double atQ = plane.heightAt(q.x, q.y) - Q.heightAt(q.x, q.y);
	return (atP > 0) != (atQ > 0) || std::abs(atP) <= pBand || std::abs(atQ) <= qBand;
}
}  // namespace

bool RrtGroundDetector::continuesPatchAtCrest(const Plane& plane, const GroundDetection& out, double tol) const
{
	// A line of nodes (m_ransac's inliers, the nodes m_remaining[i]) next to
	// an accepted extra patch (a ramp): the cable or the cable protector
	// lying across it stands above the ramp's plane; the first rows of the
	// landing past the ramp's top lie below the ramp's plane extended (a
	// convex bend), and so does the crest of any hump. Those first rows are what the
	// range of trust leaves of a landing: two rows of filled nodes (a minor
	// std of 7.5 cm, a line) in ramp_8deg_0.7m seen by a D455 1 m up (range
	// of trust 2.64 m), where the landing's cells were then judged against
	// the ramp's plane extended, 1-3 cm above them: drops. A line is a
	// crest if every one of its nodes within d_n of any accepted extra
	// patch's nodes lies below that patch's plane, and two such pairs of
	// neighbouring nodes meet as in joinsAcceptedPlane() (the line's plane
	// changes side of the patch between them, or is within the noise band
	// `tol` of it at the line's node, or within 2 tol at the patch's node).
	const double link2 = m_params.expansion_distance * m_params.expansion_distance;
	int joins = 0;
	for (size_t i : m_ransac.inliers)
	{
		const GroundNode& p = out.nodes[m_remaining[i]];
		for (const GroundNode& q : out.nodes)
		{
			if (q.plane_id < 1) continue;
			const double dx = double(p.x) - q.x, dy = double(p.y) - q.y;
			if (dx * dx + dy * dy > link2) continue;
			const Plane& Q = out.planes[size_t(q.plane_id)];
			if (double(p.z) >= Q.heightAt(p.x, p.y)) return false;  // on top of a patch: a cable, a kerb
			joins += planesMeetBetween(plane, Q, p, q, tol, 2 * tol);
		}
	}
	return joins >= 2;
}

void RrtGroundDetector::acceptPatch(const Plane& plane, size_t begin, size_t end, GroundDetection& out)
{
	const int id = int(out.planes.size());
	out.planes.push_back(plane);
	out.plane_support.push_back(end - begin);
	for (size_t a = begin; a < end; a++) out.nodes[m_patchNodes[a]].plane_id = id;
}

bool patchMeetsPlaneBetween(
	const Plane& patch, const Plane& Q, const GroundNode& p, const GroundNode& q, bool qOnGroundPlane, double tol,
	double groundInlierDistance)
{
	if (!qOnGroundPlane) return planesMeetBetween(patch, Q, p, q, tol, 2 * tol);
	if (planesMeetBetween(patch, Q, p, q, tol, tol)) return true;
	// q lies on the patch: the foot of a ramp up (or the top of a ramp down)
	// holds ground-plane nodes that are already on it, up to the ground
	// plane's inlier distance off the floor.
	if (std::abs(patch.heightAt(q.x, q.y) - double(q.z)) <= tol) return true;
	// Above the floor at q, the band of those nodes (until 2026-11-27 on
	// both sides). Below it, not: the lower level of a 5 cm step, fitted
	// over the edge's mixed cells as a plane tilted toward the floor, lay
	// 3-3.5 cm under the floor at the floor nodes by the edge and joined
	// within it, and its plane then freed the step (Kinect One, 4 m).
	const double lipAtQ = patch.heightAt(q.x, q.y) - Q.heightAt(q.x, q.y);
	return lipAtQ > 0 && lipAtQ <= tol + groundInlierDistance;
}

bool RrtGroundDetector::joinsAcceptedPlane(
	const Plane& plane, size_t begin, size_t end, const GroundDetection& out, double tol) const
{
	// Between a patch node p and an accepted node q at most d_n apart (a tree
	// step), the patch and q's plane Q meet as patchMeetsPlaneBetween() says.
	// Two such pairs (one can be a node whose window straddles an edge).
	const double link2 = m_params.expansion_distance * m_params.expansion_distance;
	int joins = 0;
	for (size_t a = begin; a < end; a++)
	{
		const GroundNode& p = out.nodes[m_patchNodes[a]];
		for (const GroundNode& q : out.nodes)
		{
			if (q.plane_id < 0) continue;
			const double dx = double(p.x) - q.x, dy = double(p.y) - q.y;
			if (dx * dx + dy * dy > link2) continue;
			const Plane& Q = out.planes[size_t(q.plane_id)];
			if (patchMeetsPlaneBetween(plane, Q, p, q, q.plane_id == 0, tol, m_params.ransac_inlier_distance) &&
				++joins >= 2)
				return true;
		}
	}
	return false;
}

}  // namespace gam
