// Ground-aware mapping for MRPT -- scene simulator: the scene text format.
//
// One statement per line; '#' starts a comment; blank lines are ignored.
// A statement is a keyword followed by key=value arguments (no spaces inside
// a value; lists are comma separated). Lengths in metres, ALL ANGLES IN
// DEGREES. World frame: +X forward, +Y left, +Z up, floor at z = 0.
// Every object needs a unique integer id >= 1; name= and category= (negative,
// small, overhang, large, ramp) are optional on every object, and so is motion
// (issue #14): frames=A-B (present only in frames A..B, 0-based; "A-" = from A on),
// move=dx,dy (metres per frame) or to=x,y (where the object's x=,y= ends up),
// moving=A-B (when it moves; default the frames= range).
//
//   floor present=1                      # present=0: no floor at all
//   kinect pose=x,y,z,yaw,pitch,roll     # on the robot; pitch>0 looks down
//          [label=KINECT]   # several kinect statements = several cameras, unique labels;
//                           # default KINECT for kinect_one, else the model in capitals (D455)
//          [model=kinect_one|d435|d455|femto|astra]  # the camera's preset (Sensors.h)
//          [noise_scale=1] [min_range=0.5] [max_range=4.5] [spike_prob=1e-4]  # override the preset
//          [flying_prob=0.5] [grazing_start=70] [grazing_end=85] [sway=0]
//        # sway: sigma [deg] of a random pitch and roll of the real sensor per
//        # frame (walker rocking), NOT reflected in the rawlog's sensorPose
//   leddar pose=x,y,z,yaw,pitch,roll [enabled=1] [sigma=0.025] [max_range=50] [vfov=3]
//   hole id= shape=rect x= y= sx= sy= [yaw=0] depth=0.06|inf     # centre, sizes
//   hole id= shape=circle x= y= r= depth=
//   box id= x= y= [z=0] sx= sy= sz= [yaw=0] [pitch=0] [roll=0]  # x,y: footprint centre, z: bottom
//   wall id= x0= y0= x1= y1= [thickness=0.10] [height=2.5]
//   stairs_down id= x= y= yaw= width= steps= rise= run= [landing=1.0]
//        # (x,y): centre of the top edge; descends along yaw; pit length
//        # steps*run + landing, depth steps*rise (its bottom is the lower floor)
//   stairs_up id= x= y= yaw= width= steps= rise= run= [top=1.0]
//        # first riser at (x,y), climbing along yaw, then a top landing
//   ramp id= x= y= yaw= length= width= angle= [sides=solid|open] [thickness=0.03]
//        [plateau=0] [back=0]
//        # rises along yaw from (x,y) (centre of the low edge); solid = wedge
//        # with side walls, open = tilted plate; plateau = flat top length;
//        # back=1 adds the symmetric way down
//   table id= x= y= [yaw=0] sx= sy= [height=0.75] [top=0.04] [leg=0.05]
//   shelf id= x= y= [yaw=0] sx= sy= sz= [boards=4] [board=0.02] [side=0.02] [bottom=0.10]
//        # two side panels + `boards` boards from `bottom` up to sz
//   path waypoints=x,y,yaw;x,y,yaw;... [spacing=0.10] [turn_spacing=5] [frames=0] [rate=10]
//        # one waypoint: `frames` frames taken there (default 1)
//   odometry_noise [xy=0] [yaw=0] [turn=0] [scale=0] [yaw_bias=0]
//        # per increment: sigma_xy = xy*dist, sigma_yaw = yaw(deg/m)*dist + turn*|dyaw|;
//        # systematic drift: the distance times (1+scale), yaw_bias (deg/m) * dist added
//   grid resolution=0.05 min_x= max_x= min_y= max_y= [robot_height=1.9]
//        [obstacle_min=0.02] [drop_min=0.02] [small_max=0.20] [overhang_clearance=0.10]
//        [max_slope=10] [subsamples=3] [per_frame=auto]
//        # per_frame=1: also the per-frame ground truth (default: when something moves)
//
// Errors throw SceneError with "file:line: message".
#pragma once

#include <istream>
#include <map>
#include <stdexcept>
#include <string>

#include "gam/sim/GroundTruth.h"
#include "gam/sim/Path.h"
#include "gam/sim/Scene.h"
#include "gam/sim/Sensors.h"

namespace gam::sim
{
class SceneError : public std::runtime_error
{
   public:
	using std::runtime_error::runtime_error;
};

/** A further depth camera on the robot (a second `kinect` statement). */
struct ExtraKinect
{
	std::string label;
	bool label_given = false;  ///< label= was set (else it follows the model)
	KinectParams params;
	std::map<std::string, double> keys;  ///< the statement's settings beside model= (kept by setCameraModel)
	Pose3 pose;
	double sway = 0;
};

struct SceneFile
{
	Scene scene;
	KinectParams kinect;
	std::map<std::string, double> kinect_keys;  ///< the statement's settings beside model=
	Pose3 kinect_pose = Pose3::fromXYZYPR(0.10, 0, 1.0, 0, 25 * M_PI / 180, 0);
	LeddarParams leddar;
	Pose3 leddar_pose = Pose3::fromXYZYPR(0.20, 0, 0.30, 0, 0, 0);
	bool leddar_enabled = true;
	double kinect_sway = 0;                 ///< radians, sigma of the per-frame pitch/roll perturbation
	std::string kinect_label = "KINECT";    ///< sensorLabel of the main camera
	bool kinect_label_given = false;        ///< label= was set (else it follows the model)
	std::vector<ExtraKinect> more_kinects;  ///< the second, third... kinect statements
	/** Write the per-frame ground truth (PREFIX_gt_frames.csv): 1 yes, 0 no, -1 = only
	 * if an object appears, disappears or moves (grid per_frame=). */
	int per_frame_truth = -1;
	PathSpec path;
	OdometryNoise odometry_noise;
	GridSpec grid;
	bool has_grid = false;
};

/** Sets a camera's settings from a `kinect` statement's keys (noise_scale,
 * min_range, max_range, spike_prob, flying_prob, grazing_start, grazing_end). */
void applyCameraKeys(KinectParams& k, const std::map<std::string, double>& keys);
/** Every camera of the scene becomes `model` (its preset), keeping the keys
 * its statement set and the noise switch (gam-simulate --camera). A camera
 * whose statement set no label= takes defaultCameraLabel(model), unless
 * another camera of the scene already carries that label (then it keeps its
 * own). */
void setCameraModel(SceneFile& sf, CameraModel model);

/** Parses a scene; `filename` is used in the error messages only. */
SceneFile parseScene(std::istream& in, const std::string& filename);
SceneFile parseSceneFile(const std::string& path);

}  // namespace gam::sim
