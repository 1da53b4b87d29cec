// Ground-aware mapping for MRPT
// RRT-GPD: ground-plane detection with a rapidly-exploring random tree grown
// over local least-squares plane fits of the 2.5D map (paper §IV.B, Alg. 1),
// followed by RANSAC on the node centres. Pure code over a read-only grid.
#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "gam/core/ElevationGrid.h"
#include "gam/core/Parameters.h"
#include "gam/core/PlaneFit.h"

namespace gam
{
struct RrtGpdParams
{
	/** `ground_aware` (default) or `paper`: Algorithm 1 as printed (see
	 * growTreePaper()): steps of exactly d_n, the normal compared with the
	 * parent's, the fallback over the nodes within d_n (lines 17-22), a
	 * window centred on the centroid of the nodes, one ground plane. */
	MethodVariant variant = MethodVariant::GroundAware;
	int iterations = 600;  ///< K
	/** N_th: a node is ground-like if the horizontal part of its local unit
	 * normal (the sine of its tilt) is at most this. 0.2 = 11.5 deg. */
	double normal_threshold = 0.2;
	/** E_th [m]: a new node's height may differ from its parent's local plane,
	 * extrapolated to the new position, by at most this. */
	double elevation_threshold = 0.05;
	int neighbourhood_x = 3;          ///< s_x [cells], odd
	int neighbourhood_y = 3;          ///< s_y [cells], odd
	double expansion_distance = 0.4;  ///< d_n [m]

	/** Cells whose height spread (std) exceeds this are not surfaces (walls,
	 * edges) and take no part in local fits. [m] */
	double max_cell_std = 0.05;
	/** A neighbourhood needs at least this many cells with a height. */
	int min_valid_cells = 5;
	/** The seed is the valid cell nearest to the robot within this radius [m]
	 * whose height is within seed_height_tolerance of the expected floor. */
	double seed_search_radius = 5.0;
	double seed_height_tolerance = 0.3;
	/** A tree that stays below min_nodes (it started on a box top or a shelf
	 * board) is discarded and regrown from the next seed candidate outside
	 * it, up to this many times. */
	int seed_attempts = 3;
	/** Margin [m] added around the explored nodes to form the sampling window. */
	double window_margin = 1.0;
	/** Fewer nodes than this: "too few nodes", no plane. */
	size_t min_nodes = 8;
	/** RANSAC over the node centres. */
	int ransac_iterations = 100;
	double ransac_inlier_distance = 0.025;  ///< [m]
	/** Extra planes (ramps) need this many supporting nodes; 0 disables them. */
	size_t min_nodes_per_extra_plane = 3;
	/** The ground plane + extra patches. A ramp with a landing and a way down
	 * is three patches next to the floor (see fill_patches). */
	int max_planes = 4;
	/** After the tree: from every node off the ground plane (a ramp or landing
	 * the tree climbed onto) or whose local plane leaves it by more than
	 * ransac_inlier_distance within d_n (a ramp's foot), add nodes s_x by s_y
	 * cells apart in the 8 directions, with the tree's own tests (E_th
	 * against the parent's local plane, N_th), until the surface
	 * meets the ground plane again or K nodes were added. The random
	 * tree puts a node every ~d_n and reaches a narrow ramp only through its
	 * foot: a 0.7 m wide 8 deg ramp got a handful of nodes near its foot in
	 * 4 of 11 frames, too few (and too collinear) for a patch of its own;
	 * filled, its nodes tile it with their own fit windows. Only within
	 * GroundSeedHint::fill_range of the sensor. Not in the paper variant. */
	bool fill_patches = true;
	uint32_t random_seed = 1;

	/** The .ini keys (paper Table I names), ranges and meanings (Parameters.h). */
	template <class Self, class Visit>
	static void forEachParam(Self& p, Visit&& visit)
	{
		visit(
			ParamInfo{
				"rrt_variant", 0, 1, "RRT-GPD: ground_aware | paper (Algorithm 1 as printed)", kMethodVariantNames},
			p.variant);
		visit(ParamInfo{"K", 1, 1000000, "RRT-GPD iterations"}, p.iterations);
		visit(
			ParamInfo{"N_th", 1e-6, 1, "max horizontal part of a node's unit normal (sin of tilt)"},
			p.normal_threshold);
		visit(ParamInfo{"E_th", 1e-6, 10, "max height step from the parent's local plane [m]"}, p.elevation_threshold);
		visit(ParamInfo{"s_x", 3, 31, "local fit neighbourhood along x [cells, odd]"}, p.neighbourhood_x);
		visit(ParamInfo{"s_y", 3, 31, "local fit neighbourhood along y [cells, odd]"}, p.neighbourhood_y);
		visit(ParamInfo{"d_n", 1e-3, 100, "node expansion distance [m]"}, p.expansion_distance);
		visit(ParamInfo{"max_cell_std", 1e-6, 10, "cells rougher than this are not surfaces [m]"}, p.max_cell_std);
		visit(ParamInfo{"min_valid_cells", 3, 961, "cells with a height a local fit needs"}, p.min_valid_cells);
		visit(
			ParamInfo{"seed_search_radius", 1e-3, 1000, "seed within this distance of the robot [m]"},
			p.seed_search_radius);
		visit(ParamInfo{"seed_height_tolerance", 1e-3, 100, "seed height vs robot floor [m]"}, p.seed_height_tolerance);
		visit(ParamInfo{"seed_attempts", 1, 100, "seeds tried when a tree stays too small"}, p.seed_attempts);
		visit(ParamInfo{"window_margin", 1e-3, 1000, "sampling window margin around the nodes [m]"}, p.window_margin);
		visit(ParamInfo{"min_nodes", 3, 1000000, "fewer tree nodes = no ground"}, p.min_nodes);
		visit(ParamInfo{"ransac_iterations", 1, 1000000, "RANSAC iterations on the nodes"}, p.ransac_iterations);
		visit(ParamInfo{"ransac_inlier_distance", 1e-6, 10, "RANSAC inlier distance [m]"}, p.ransac_inlier_distance);
		visit(
			ParamInfo{"min_nodes_per_extra_plane", 0, 1000000, "nodes an extra ground patch (ramp) needs; 0 = none"},
			p.min_nodes_per_extra_plane);
		visit(ParamInfo{"max_planes", 1, 8, "ground plane + extra patches"}, p.max_planes);
		visit(
			ParamInfo{
				"fill_patches", 0, 1,
				"add nodes s_x x s_y cells apart over ground off the main plane (ramps), with the tree's tests"},
			p.fill_patches);
		visit(ParamInfo{"random_seed", 0, 2147483647, "RNG seed (same seed, same result)"}, p.random_seed);
	}
	/** Throws std::invalid_argument naming the parameter out of range. */
	void validate() const;
};

/** Index of the point (xs[i], ys[i]), i < n, nearest to (qx, qy), its squared
 * distance in d2; n must be > 0. Exact: the distance is computed as nanoflann's
 * L2_Simple_Adaptor<float> does ((qx - x)^2 + (qy - y)^2 in float, each
 * operation rounded, no fused multiply-add), and on an exact tie the lowest
 * index wins. RRT-GPD's nearest-node query. */
uint32_t nearestPoint(const float* xs, const float* ys, size_t n, float qx, float qy, float& d2);

struct GroundNode
{
	float x = 0, y = 0, z = 0;  ///< centre (cell centre, surface height)
	Plane local;                ///< least-squares plane of its s_x * s_y neighbourhood
	float fit_rms = 0;          ///< RMS residual of that fit [m]
	int parent = -1;
	int plane_id = -1;  ///< index into GroundDetection::planes, -1 = none

	/** The node at cell centre (x, y) whose local fit is `local` (RMS `rms`):
	 * its height is that plane's there. */
	static GroundNode fromFit(double x, double y, const Plane& local, double rms, int parent)
	{
		GroundNode n;
		n.x = float(x);
		n.y = float(y);
		n.z = float(local.heightAt(x, y));
		n.local = local;
		n.fit_rms = float(rms);
		n.parent = parent;
		return n;
	}
};

struct GroundDetection
{
	enum class Status
	{
		Ok,
		EmptyGrid,    ///< no observed cell at all
		NoValidSeed,  ///< nothing planar near the robot at floor height
		TooFewNodes,  ///< the tree did not grow: no floor of useful size
		NoConsensus   ///< RANSAC found no plane among the nodes
	};
	Status status = Status::EmptyGrid;
	/** planes[0] is the ground plane: the plane the seed (the floor under the
	 * robot) lies on, grown from the seed's local plane, even when a ramp or
	 * landing in view has more nodes (the paper variant: the largest RANSAC
	 * consensus). Later ones are smaller ground patches (ramps): connected
	 * areas of at least min_nodes_per_extra_plane nodes. */
	std::vector<Plane> planes;
	std::vector<size_t> plane_support;  ///< nodes per plane
	std::vector<GroundNode> nodes;      ///< nodes[0] is the seed; fill_patches nodes follow the tree's
	size_t fill_nodes = 0;              ///< nodes added by fill_patches (the last ones)
	/** The inlier distance the extra patches were fitted with [m]: 3 sigma of
	 * the ground plane's nodes about it (1.4826 x their median absolute
	 * distance) + d_r / 2 * tan(asin N_th), at most ransac_inlier_distance.
	 * The ground plane itself is refitted to its nodes within the same kind
	 * of band about the seed's local plane. */
	double patch_inlier_distance = 0;
	int iterations = 0;
	/** planes[0] is the mount's floor, not the tree's plane: the tree's was
	 * farther from the robot's floor than max_ground_offset under the robot
	 * (the pipeline), or held significantly fewer of the nodes than that
	 * floor (GroundSeedHint::judge_against_floor). */
	bool ground_from_mount = false;
	Plane tree_plane;  ///< the tree's plane when ground_from_mount (the mount check measures it)
	/** planes[remembered_from..] are patches of earlier frames (PatchMemory),
	 * which apply only where none of this frame's patches does; 0 = none. */
	size_t remembered_from = 0;

	bool ok() const { return status == Status::Ok; }
	const Plane& plane() const { return planes.front(); }
	/** Back to the default state; the vectors keep their capacity, so reusing
	 * one GroundDetection frame after frame allocates nothing. */
	void clear()
	{
		status = Status::EmptyGrid;
		planes.clear();
		plane_support.clear();
		nodes.clear();
		fill_nodes = 0;
		patch_inlier_distance = 0;
		iterations = 0;
		ground_from_mount = false;
		remembered_from = 0;
	}
	static const char* statusName(Status s);
	std::string describe() const;
};

/** Expected floor: where the robot stands. */
struct GroundSeedHint
{
	double x = 0, y = 0;  ///< robot position in the grid frame
	double floor_z = 0;   ///< expected floor height in the grid frame
	/** The range (2D, from the sensor) within which the map takes evidence:
	 * the camera's range of trust. fill_patches adds no node beyond it
	 * (patches there would judge cells that get none), and only the ground
	 * nodes within it give the extra patches' inlier distance (the noise
	 * where the patches judge cells, not that of far floor). */
	double fill_range = std::numeric_limits<double>::infinity();
	double sensor_x = 0, sensor_y = 0;  ///< sensor position in the grid frame
	/** The floor at floor_z (level) is what the mount predicts: where the
	 * ground plane grown from the seed holds significantly fewer of the
	 * nodes than that floor does (floorHoldsMoreNodes at kFloorTestSigmas),
	 * that floor is the ground plane and the patches are fitted around it
	 * (GroundDetection::ground_from_mount; the pipeline sets it with
	 * max_ground_offset > 0). */
	bool judge_against_floor = false;

	/** The floor the mount predicts: level, at floor_z. */
	Plane floorPlane() const { return Plane{0, 0, 1, -floor_z}; }
	bool withinFillRange(double px, double py) const
	{
		const double dx = px - sensor_x, dy = py - sensor_y;
		return dx * dx + dy * dy <= fill_range * fill_range;
	}
};

/** How many standard deviations floorHoldsMoreNodes() asks of the
 * difference (the 3 sigma of the rest of the method). */
constexpr double kFloorTestSigmas = 3.0;

/** Whether `floor` holds significantly more of `nodes` than `plane` does,
 * each holding the nodes within `inlierDistance` of it: of the nodes only
 * one of them holds, the floor's count exceeds the plane's by more than k
 * standard deviations of that difference under "neither is better"
 * (McNemar's test: k sqrt(floor's + plane's)). */
bool floorHoldsMoreNodes(
	const std::vector<Eigen::Vector3d>& nodes, const Plane& plane, const Plane& floor, double inlierDistance, double k);

/** Whether an extra ground patch (plane `patch`, on node p) and an accepted
 * plane Q (on node q, at most a tree step from p) meet between p and q rather
 * than across a step (see RrtGroundDetector::fitPlanes):
 *  - the patch's height over Q changes sign from p to q (they cross), or
 *  - it is within `tol` (the patches' noise band) of Q at p, or at q within
 *    `tol` (2 `tol` where Q is another patch);
 *  - where Q is the ground plane also: the patch passes within `tol` of q
 *    itself (q lies on it), or stands above Q at q by at most `tol` +
 *    `groundInlierDistance` (the ground plane's RANSAC inlier distance).
 * A patch below the floor at q by more than `tol`, and below q too, does not
 * meet it: the lower level of a step down. */
bool patchMeetsPlaneBetween(
	const Plane& patch, const Plane& Q, const GroundNode& p, const GroundNode& q, bool qOnGroundPlane, double tol,
	double groundInlierDistance);

/** The slope of a ground patch, measured twice: by the plane through its
 * nodes' centres (`nodesGradient`, dz/dx and dz/dy; the centres' residual
 * variance about it `residualVariance`, their 2D covariance `spread`) and by
 * the nodes' own local planes (`localGradients`, one per node). Along each
 * principal axis e of `spread` (eigenvalue lambda), the centres' plane has
 * the variance residualVariance / (n lambda) (a least-squares slope over n
 * points of that spread) and the mean of the local slopes its sample variance
 * / n; the result is their inverse-variance weighted mean on each axis (a
 * zero variance wins outright). Across a line of nodes lambda -> 0 and the
 * local planes give the roll; along a patch its centres give the slope. */
Eigen::Vector2d combinedPatchGradient(
	const Eigen::Vector2d& nodesGradient, double residualVariance, const Eigen::Matrix2d& spread,
	const std::vector<Eigen::Vector2d>& localGradients);

/** Algorithm 1's search window (rrt_variant = paper): centred on the centroid
 * of the explored nodes, so it drifts toward them as the tree grows; its half
 * side along each axis is the nodes' largest offset from the centroid plus a
 * margin, cut to the grid. */
struct PaperSearchWindow
{
	double sum_x = 0, sum_y = 0;
	size_t nodes = 0;
	double x_lo = 0, x_hi = 0, y_lo = 0, y_hi = 0;  ///< bounding box of the nodes

	void add(double x, double y)
	{
		x_lo = nodes ? std::min(x_lo, x) : x;
		x_hi = nodes ? std::max(x_hi, x) : x;
		y_lo = nodes ? std::min(y_lo, y) : y;
		y_hi = nodes ? std::max(y_hi, y) : y;
		sum_x += x;
		sum_y += y;
		nodes++;
	}
	/** The window [x0, x1] x [y0, y1] (needs one node at least). */
	void bounds(const GridGeometry& g, double margin, double& x0, double& x1, double& y0, double& y1) const
	{
		const double mx = sum_x / double(nodes), my = sum_y / double(nodes);
		const double hx = std::max(mx - x_lo, x_hi - mx) + margin, hy = std::max(my - y_lo, y_hi - my) + margin;
		x0 = std::max(g.x_min, mx - hx);
		x1 = std::min(g.x_max(), mx + hx);
		y0 = std::max(g.y_min, my - hy);
		y1 = std::min(g.y_max(), my + hy);
	}
};

class RrtGroundDetector
{
   public:
	/** Throws std::invalid_argument for parameters out of range. */
	explicit RrtGroundDetector(const RrtGpdParams& p = {}) { setParams(p); }
	/** Validates (throws std::invalid_argument), then keeps `p`: detect() runs
	 * with parameters checked once, not on every frame. */
	void setParams(const RrtGpdParams& p)
	{
		p.validate();
		m_params = p;
	}
	const RrtGpdParams& params() const { return m_params; }

	/** Runs Algorithm 1 on `grid`. Deterministic for equal inputs and seed.
	 * Reuses its buffers and `out`'s vectors: after the first call with a given
	 * grid size and parameters it makes no heap allocation. */
	void detect(const ElevationGrid& grid, const GroundSeedHint& hint, GroundDetection& out);

	/** Local least-squares plane of the s_x * s_y cells around (cx, cy), using
	 * observed heights and IDW estimates. False if too few cells or degenerate. */
	bool fitLocalPlane(const ElevationGrid& grid, int cx, int cy, Plane& plane, double& rms) const;
	/** Paper variant, Algorithm 1 line 14 as printed (exposed for tests): the
	 * new node's local plane at (px, py) is within E_th of x_near's height,
	 * |plane_local(z) - x_near(z)| <= E_th. */
	bool paperElevationOk(const GroundNode& near, double px, double py, const Plane& pl) const;
	/** Paper variant, the normal test of lines 15 and 18 (exposed for tests):
	 * the sine of the angle between the new local normal and `node`'s is at
	 * most N_th (our reading: as printed, n_new . n_near <= N_th accepts only
	 * nearly perpendicular normals). */
	bool paperNormalOk(const GroundNode& node, const Plane& pl) const;

   private:
	bool cellHeight(const ElevationGrid& grid, int cx, int cy, float& z) const;
	/** A local fit the tree accepts: normal within N_th of vertical. */
	bool planarEnough(const Plane& local) const;
	/** rrt_variant = paper: Algorithm 1 and one RANSAC plane, without the
	 * default's guards (max_cell_std, min_valid_cells, the seed's height,
	 * re-seeding, min_nodes, RANSAC's tilt limit and refit, the
	 * collinear-nodes rule). */
	bool paper() const { return m_params.variant == MethodVariant::Paper; }
	/** Nodes a tree needs: min_nodes, or the 3 of a plane in the paper's variant. */
	size_t minNodes() const { return paper() ? 3 : m_params.min_nodes; }
	/** The child `parent` (index parentIdx) would get at cell (cx, cy): the
	 * cell's height within E_th of the parent's local plane there, its own
	 * local fit planarEnough(). False if a test fails (`child` undefined). */
	bool childAt(
		const ElevationGrid& grid, const GroundNode& parent, int parentIdx, int cx, int cy, GroundNode& child) const;
	bool findSeed(const ElevationGrid& grid, const GroundSeedHint& hint, GroundNode& seed);
	/** Empties the tree (and its node index) and plants `seed`: both variants. */
	void startTree(const GridGeometry& g, const GroundNode& seed, GroundDetection& out);
	/** Appends `node` (in cell (cx, cy)) to the tree and its index. */
	void addTreeNode(const GridGeometry& g, const GroundNode& node, int cx, int cy, GroundDetection& out);
	void growTree(const ElevationGrid& grid, const GroundNode& seed, GroundDetection& out);
	void growTreePaper(const ElevationGrid& grid, const GroundNode& seed, GroundDetection& out);
	std::vector<std::pair<float, uint32_t>> m_candidates;  ///< paper fallback: (distance^2, node)
	/** The planes of out.nodes, from scratch (earlier planes and node labels dropped). */
	void fitPlanes(GroundDetection& out);
	/** The ground plane grown from the seed's local plane (see fitPlanes),
	 * or the hint's floor where that holds significantly more of the nodes
	 * (GroundSeedHint::judge_against_floor; then ground_from_mount, and
	 * tree_plane the seed's plane); false if it has fewer than
	 * rp.min_inliers nodes. Into m_ransac. */
	bool groundFromSeed(GroundDetection& out, const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp);
	/** Keeps, of m_ransac's inliers, the largest group linked by steps of at
	 * most d_n, and refits its plane (see fitPlanes). */
	void keepLargestCluster(const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp);
	/** Refits m_ransac.plane (total least squares) to the points of its
	 * inliers, unless that plane tilts beyond N_th. */
	void refitToInliers(const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp);
	/** Drops from m_ransac's inliers the nodes whose local plane parts from
	 * the patch across a fit window by more than the inlier distance and the
	 * noise of their own slope (a crease), and refits (see fitPlanes). */
	void dropCreaseNodes(const GroundDetection& out, const std::vector<Eigen::Vector3d>& pts, const RansacParams& rp);
	/** 3 sigma of the distances in m_absDist (robust) + the cell quantisation
	 * d_r / 2 * tan(asin N_th), at most `cap` (see fitPlanes). */
	double noiseBand(double cap);
	/** True if the patch `plane` (on the nodes m_patchNodes[begin, end)) meets
	 * an accepted plane between neighbouring nodes, not across a step of more
	 * than `tol` (see fitPlanes). */
	bool joinsAcceptedPlane(const Plane& plane, size_t begin, size_t end, const GroundDetection& out, double tol) const;
	/** The plane through the centroid of m_ransac's inliers (indices into
	 * `pts`, the nodes m_remaining[i]; `spread`: their 2D covariance) with
	 * the combinedPatchGradient() of their centres and local planes. */
	Plane patchFromNodesAndNormals(
		const GroundDetection& out, const std::vector<Eigen::Vector3d>& pts, const Eigen::Matrix2d& spread);
	std::vector<Eigen::Vector2d> m_localGradients;
	/** True if m_ransac's inliers, a line of nodes with plane `plane`, are
	 * the crest of an accepted extra patch: below its plane wherever they
	 * are within d_n of its nodes, and joining it (see fitPlanes). */
	bool continuesPatchAtCrest(const Plane& plane, const GroundDetection& out, double tol) const;
	/** Appends `plane` as a patch held by the nodes m_patchNodes[begin, end). */
	void acceptPatch(const Plane& plane, size_t begin, size_t end, GroundDetection& out);
	std::vector<int> m_cluster;
	std::vector<size_t> m_bfs;
	/** fill_patches: adds nodes over the ground off `ground` (see RrtGpdParams). */
	void fillPatches(const ElevationGrid& grid, const Plane& ground, GroundDetection& out);
	std::vector<uint32_t> m_fillQueue;
	double m_resolution = 0.05;  ///< of the grid in detect() [m]
	GroundSeedHint m_hint;       ///< of the frame in detect()
	/** groundFromSeed judges the ground plane against the hint's floor: the
	 * tree kept, not the trees compared by rule R10 (detect()). */
	bool m_judgeAgainstFloor = false;
	/** The plane groundFromSeed grew from the seed in the last fitPlanes(),
	 * before any test against the floor (m_seedPlaneFitted: it did). */
	Plane m_seedPlane;
	bool m_seedPlaneFitted = false;
	std::vector<double> m_absDist;
	void reserveScratch(const GridGeometry& g);
	size_t maxTreeNodes(const GridGeometry& g) const;

	// Nearest tree node to a query point (the "nodes in a k-d tree" of the
	// paper): every node's centre tested, from arrays of the centres.
	void nodeIndexReset();
	void nodeIndexAdd(const GroundNode& node);
	uint32_t nodeIndexNearest(float qx, float qy, float& d2) const;

	RrtGpdParams m_params;
	std::mt19937 m_rng;
	std::mt19937 m_rngAtFirst;  ///< m_rng before a tree that detect() may grow again
	// Scratch, reused between frames (cleared, never shrunk): after the first
	// frame of a given grid size and parameters, detect() allocates nothing.
	std::vector<uint8_t> m_hasNode;
	std::vector<uint32_t> m_nodeCells;
	mutable std::vector<Eigen::Vector3d> m_fitPts;
	std::vector<std::pair<int, int>> m_ringOffsets;
	std::vector<uint8_t> m_seedExcluded;
	int m_ringRadius = -1;
	// Node index: the tree's node centres in node order (x and y apart, so
	// that four are tested at once).
	std::vector<float> m_nodeX, m_nodeY;
	// fitPlanes():
	std::vector<size_t> m_remaining, m_rest;
	std::vector<uint8_t> m_flag;
	std::vector<Eigen::Vector3d> m_ransacPts, m_ransacInliers;
	RansacResult m_ransac;
	// Extra patches set aside until a plane they join is accepted: their
	// nodes in m_patchNodes[begin, end).
	struct DeferredPatch
	{
		Plane plane;
		size_t begin = 0, end = 0;
		bool taken = false;
	};
	std::vector<DeferredPatch> m_deferred;
	std::vector<size_t> m_patchNodes;
};

}  // namespace gam
