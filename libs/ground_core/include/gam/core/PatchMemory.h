// Ground-aware mapping for MRPT
// The ramp patches one camera's earlier frames found (issue #27). A ramp does
// not move, but a frame may see too little of it for a patch of its own: a
// sliver at the side of the view, the foot left before a cable, or a tree
// whose random draws missed it. Judged against the floor plane, its cells then
// stand 2-12 cm above the floor and become obstacles, although an earlier
// frame of the same camera fitted the ramp. The pipeline keeps the sloped
// patches that two or more of its frames fitted (in the map frame) and offers
// them to the ISM beside the frame's own planes, where none of the frame's
// own patches applies: each voxel is still judged against the plane it fits
// best (InverseSensorModel::choosePlane), within plane_support_radius of the
// patch's nodes, so a box now standing on a remembered ramp fits neither and
// stays an obstacle. Pure code: no I/O.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "gam/core/PlaneFit.h"
#include "gam/core/RrtGroundDetector.h"

namespace gam
{
class PatchMemory
{
   public:
	PatchMemory();

	/** Forgets every patch and the path travelled (a new map, a new run). */
	void clear();

	/** The robot's path length over the frames [m], after a frame taken at
	 * `robot` (map frame, x y): the `travelled` that apply() takes. */
	double advance(const Eigen::Vector2d& robot);

	/** The detection to judge this frame with, and the memory updated.
	 * - `det`: this frame's (planes[0] the ground, planes[1..] its patches);
	 * - `travelled`: the robot's path length so far [m];
	 * - `forgetAfter`: a patch not seen again within this much travel is
	 *   forgotten (odometry drift moves it against the frame) [m]; 0 = no
	 *   memory (returns `det`, remembers nothing);
	 * - `band`: a patch of this frame with a node within `reach` of a
	 *   remembered patch's nodes, whose height differs from it by at most
	 *   `band` at every one of them, repeats it (the frame's patch band) [m];
	 * - `rise`: only patches that rise across their nodes by more than this
	 *   are remembered (sloped(); the smallest hazard, traversable_step) [m].
	 * Returns `det` itself when no remembered patch applies, else a copy of
	 * its planes and patch nodes (the ISM's inputs) with the remembered
	 * patches that no patch of this frame repeats appended (their nodes'
	 * plane_id set), at most 8 planes in all (the ISM's support bits). Then
	 * remembers this frame's patches and the remembered ones it kept. The
	 * reference is valid until the next call. */
	const GroundDetection& apply(
		const GroundDetection& det, double travelled, double forgetAfter, double band, double reach, double rise);

	/** Keeps the memory (patches and path) as it is now; restore() brings it
	 * back (a frame that ran ahead on inputs that changed runs again:
	 * CGroundAwareOccupancyGrid with threads > 1). No allocation once warm. */
	void save();
	void restore();

	/** Patches remembered after the last apply(). */
	size_t size() const { return m_patches.size(); }
	/** One remembered patch: its plane (map frame), how many frames fitted
	 * it (each repeating the last), the path length when one last did. */
	struct Remembered
	{
		Plane plane;
		int frames = 0;
		double seen_at = 0;  ///< [m]
	};
	/** Patch k of size() (k < size()). */
	Remembered patch(size_t k) const
	{
		const Patch& p = m_patches[k];
		return {p.plane, p.frames, p.seen_at};
	}
	/** The robot's path length over the frames so far [m]. */
	double travelled() const { return m_path.travelled; }
	/** Of the last apply(): remembered patches appended to the frame's. */
	size_t applied() const { return m_applied; }

	static constexpr size_t kMaxPlanes = 8;           ///< the ISM's support bits per block
	static constexpr size_t kMaxNodesPerPatch = 256;  ///< nodes kept of one patch
	/** Frames that must have fitted a patch before it judges others: one
	 * frame's tree can fit a patch to the top of a cable protector (3 nodes
	 * about 3.2 cm up in cable_protector, Kinect One), which remembered for
	 * 1 m of travel freed part of it in the next 9 frames (coverage 1.00 ->
	 * 0.89). */
	static constexpr int kMinFrames = 2;

	/** Whether patch k of `det` rises across its own nodes, along its
	 * gradient, by more than `rise`: a surface the tree reached without a
	 * step whose height changes by more than the smallest hazard over its
	 * extent is a ramp. Only those are remembered: a raised patch that rises
	 * less can be an object's top that trees fit now and then (the 4 cm
	 * protector of cable_protector, level, 3-4 nodes 3.4 cm up, in 4 of its
	 * first 10 frames with the Kinect One and random_seed 4; a 4.2 cm one of
	 * the held-out seed_3007, 12-13 nodes tilted 1.9-2.8 deg by the noise at
	 * 3.3 m, rising 13 mm across them, in two frames in a row). */
	static bool sloped(const GroundDetection& det, size_t k, double rise);

   private:
	struct Patch
	{
		Plane plane;
		double seen_at = 0;           ///< path length when a frame last fitted it [m]
		int frames = 1;               ///< frames that fitted it, each repeating the last
		uint32_t begin = 0, end = 0;  ///< its nodes in m_nodes
	};
	/** The patch of this frame that is the same surface as `p`, 0 if none. */
	size_t repeatedBy(const Patch& p, const GroundDetection& det, double band, double reach) const;

	std::vector<Patch> m_patches, m_next;
	std::vector<Eigen::Vector2f> m_nodes, m_nextNodes;
	std::vector<Patch> m_savedPatches;
	std::vector<Eigen::Vector2f> m_savedNodes;
	/** The path: its length, and where the last frame was taken. */
	struct Path
	{
		double travelled = 0;
		Eigen::Vector2d last = Eigen::Vector2d::Zero();
		bool started = false;
	};
	Path m_path, m_savedPath;
	std::vector<uint8_t> m_keep;
	std::vector<int> m_frames;  ///< per plane of this frame
	GroundDetection m_augmented;
	size_t m_applied = 0;
};

}  // namespace gam
