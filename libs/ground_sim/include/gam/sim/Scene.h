// Ground-aware mapping for MRPT -- scene simulator (pure code, Eigen only).
// Scene geometry and exact ray casting.
//
// The world frame is MRPT's: +X forward, +Y left, +Z up, the floor is the
// plane z = 0. A scene is the floor (solid below z = 0) with "holes" carved
// out of it (rectangular or circular pits of a given depth, or bottomless),
// plus a list of convex solids (boxes, wedges) placed in the world. Every
// composite primitive of the scene file (stairs, table, shelf, ramp, wall)
// is expanded by the parser into these two kinds, all parts keeping the
// object id of the primitive they come from.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <limits>
#include <string>
#include <vector>

namespace gam::sim
{
/** Object categories written in the ground truth (see GroundTruth.h). */
enum class Category : int
{
	None = 0,      ///< plain floor
	Negative = 1,  ///< below the floor: holes, outlets, downward stairs
	Small = 2,     ///< obstacle lower than GroundTruthParams::small_max_height
	Overhang = 3,  ///< has a part floating above the floor (table top, shelf boards)
	Large = 4,     ///< any other obstacle
	Ramp = 5       ///< traversable slope (label free)
};
const char* categoryName(Category c);
/** Parses "negative", "small", ... (returns false if unknown). */
bool categoryFromName(const std::string& s, Category& c);

/** How a surface answers a depth camera's or the Leddar's light (issue #13).
 * Normal: the sensor models of Sensors.h. Absorbing: black or absorbing, no
 * return at all. Transparent: clear glass or plastic, the light passes (the
 * sensors see what is behind; the ground truth still has the object).
 * Specular: a shiny floor patch, each pixel drops out with probability
 * `dropout` (ObjectInfo), on top of the normal model. */
enum class Material : int
{
	Normal = 0,
	Absorbing,
	Transparent,
	Specular
};
const char* materialName(Material m);
/** Parses "normal", "absorbing", "transparent", "specular". */
bool materialFromName(const std::string& s, Material& m);

/** A rigid pose: p_world = R * p_local + t. */
struct Pose3
{
	Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
	Eigen::Vector3d t = Eigen::Vector3d::Zero();
	/** MRPT CPose3D convention: R = Rz(yaw) * Ry(pitch) * Rx(roll), angles in
	 * radians. Positive pitch turns +X towards -Z (nose down). */
	static Pose3 fromXYZYPR(double x, double y, double z, double yaw, double pitch, double roll);
	Pose3 operator*(const Pose3& o) const;  ///< composition (this ⊕ o)
	Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return R * p + t; }
	/** yaw, pitch, roll (radians) of R in the same convention. */
	Eigen::Vector3d ypr() const;
};

/** A convex solid = intersection of half-spaces n·p <= d (n outward, unit). */
struct ConvexSolid
{
	std::vector<Eigen::Vector3d> n;
	std::vector<double> d;
	Eigen::AlignedBox3d bbox;  ///< world-space bounds, for culling
	int object_id = 0;
	bool transparent = false;  ///< rays pass through it (Material::Transparent)

	/** An oriented box: local frame centred on the box, half sizes h. */
	static ConvexSolid box(const Pose3& centre, const Eigen::Vector3d& halfSize, int id);
	/** A ramp wedge: rising along local +X from 0 to `length`, width `width`
	 * (local Y centred), height length*tan(angle). Local origin = bottom of the
	 * low edge, centre of its width. */
	static ConvexSolid wedge(const Pose3& origin, double length, double width, double angleRad, int id);
	/** Adds a half-space; `p` any point on its plane. */
	void addPlane(const Eigen::Vector3d& normal, const Eigen::Vector3d& p);
	bool contains(const Eigen::Vector3d& p, double eps = 1e-9) const;
	/** Ray p(t) = o + t*dir, t in [tmin,tmax]. On entry hit, returns true with
	 * t and the outward normal of the entry face. A ray starting inside
	 * reports no hit. */
	bool intersect(
		const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, double tmax, double& t,
		Eigen::Vector3d& normal) const;
	/** Vertical extent of the solid over (x,y); false if the line misses it. */
	bool verticalExtent(double x, double y, double& zmin, double& zmax) const;
};

/** A pit carved into the floor from z = 0 down to z = -depth (depth may be
 * +inf: bottomless). Rectangle (yawed) or circle. */
struct Hole
{
	enum Shape
	{
		Rect,
		Circle
	} shape = Rect;
	double cx = 0, cy = 0;  ///< centre
	double hx = 0, hy = 0;  ///< half sizes (Rect)
	double yaw = 0;         ///< radians (Rect)
	double r = 0;           ///< radius (Circle)
	double depth = 0.1;     ///< metres, > 0, may be infinity
	int object_id = 0;

	bool containsXY(double x, double y) const;
	/** Interior of the pit volume (open above, below z=0): strict xy inside and
	 * z > -depth. */
	bool containsXYZ(const Eigen::Vector3d& p) const { return containsXY(p.x(), p.y()) && p.z() > -depth; }
	/** Where a ray inside the pit leaves it through its walls or bottom
	 * (t > tmin). Sets the inward-facing normal of the surface hit. Returns
	 * +inf if it never leaves (bottomless, going down). */
	double exitT(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, Eigen::Vector3d& normal) const;
};

/** Static description of a scene object (for the ground-truth list). */
struct ObjectInfo
{
	int id = 0;
	std::string name;
	std::string type;  ///< primitive keyword: box, hole, stairs_down, ...
	Category category = Category::Large;
	bool category_given = false;  ///< set explicitly in the scene file
	bool traversable = false;     ///< ramps within the slope limit (set by GroundTruthGrid::build)
	Material material = Material::Normal;
	double dropout = 0;        ///< Specular: per-pixel dropout probability
	double slope_deg = 0;      ///< ramps: surface slope
	Eigen::AlignedBox3d bbox;  ///< at the object's first placement (frame first_frame)

	// Motion over the frames (issue #14): present in frames first_frame..last_frame
	// (0-based, inclusive); moved by move_per_frame per frame in move_first..move_last
	// (held before and after). A static object has the defaults.
	int first_frame = 0;
	int last_frame = std::numeric_limits<int>::max();
	int move_first = 0, move_last = 0;
	Eigen::Vector2d move_per_frame = Eigen::Vector2d::Zero();
	bool dynamic() const
	{
		return first_frame > 0 || last_frame != std::numeric_limits<int>::max() || !move_per_frame.isZero(0);
	}
	bool presentAt(int frame) const { return frame >= first_frame && frame <= last_frame; }
	/** Translation (x, y) of the object at `frame` from its placement in the scene file. */
	Eigen::Vector2d offsetAt(int frame) const
	{
		const int f = std::clamp(frame, move_first, std::max(move_first, move_last));
		return move_per_frame * double(f - move_first);
	}
};

/** A patch of floor with its own material (a black mat, a shiny tile):
 * no geometry, the floor's hits inside it take the patch's object id. */
struct FloorPatch
{
	double cx = 0, cy = 0, hx = 0, hy = 0, yaw = 0;
	int object_id = 0;
	bool containsXY(double x, double y) const;
};

/** Result of one ray cast. */
struct RayHit
{
	bool hit = false;
	double t = std::numeric_limits<double>::infinity();  ///< ray parameter
	Eigen::Vector3d point = Eigen::Vector3d::Zero();
	Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< surface normal, facing the ray origin side
	int object_id = 0;                                  ///< 0 = plain floor
};

class Scene
{
   public:
	bool has_floor = true;  ///< floor plane z=0 (solid below)
	std::vector<Hole> holes;
	std::vector<ConvexSolid> solids;
	std::vector<ObjectInfo> objects;
	std::vector<FloorPatch> floor_patches;

	/** Nearest surface along o + t*dir for t in (tmin, tmax]. `dir` need not be
	 * unit: t is in units of |dir|. Exact for the floor, the pits and the
	 * convex solids. */
	RayHit cast(
		const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin = 0.0,
		double tmax = std::numeric_limits<double>::infinity()) const;

	/** Is p inside solid matter (floor or a solid)? */
	bool insideMatter(const Eigen::Vector3d& p) const;

	const ObjectInfo* object(int id) const;
	/** The material of the surface of object `id` (0: plain floor). */
	Material materialOf(int id) const;
	/** Bounding box of all the solids and holes (the floor is unbounded). */
	Eigen::AlignedBox3d bounds() const;

	/** Does any object appear, disappear or move over the frames? */
	bool dynamic() const;
	/** The scene as it is in frame `frame`: the parts of absent objects removed, those
	 * of moving objects translated (ObjectInfo::presentAt, offsetAt). `objects` is kept
	 * whole. A static scene gives a copy of itself. */
	Scene atFrame(int frame) const;
	/** xy bounds of object `id`'s parts as placed in `frame` (empty if absent then). */
	Eigen::AlignedBox2d footprintAt(int id, int frame) const;

   private:
	/** Floor+pits only. */
	bool castGround(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, double tmax, RayHit& h) const;
};

}  // namespace gam::sim
