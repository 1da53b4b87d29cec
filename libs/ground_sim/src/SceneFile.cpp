// Ground-aware mapping for MRPT -- scene simulator: scene text parser (format in SceneFile.h).
#include "gam/sim/SceneFile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace gam::sim
{
namespace
{
constexpr double kDeg = M_PI / 180.0;

/** The key=value arguments of one statement; every error names the file, line and
 * keyword. */
class Args
{
   public:
	Args(const std::string& kw, const std::string& where) : m_kw(kw), m_where(where) {}
	const std::string& keyword() const { return m_kw; }
	[[noreturn]] void fail(const std::string& msg) const { throw SceneError(m_where + ": " + m_kw + ": " + msg); }
	void add(const std::string& tok)
	{
		const auto eq = tok.find('=');
		if (eq == std::string::npos || eq == 0 || eq + 1 == tok.size()) fail("expected key=value, got '" + tok + "'");
		const std::string k = tok.substr(0, eq);
		if (m_kv.count(k)) fail("duplicate key '" + k + "'");
		m_kv[k] = tok.substr(eq + 1);
	}
	bool has(const std::string& k) const { return m_kv.count(k) != 0; }
	std::string str(const std::string& k, const std::string& def = std::string(), bool req = false)
	{
		auto it = m_kv.find(k);
		if (it == m_kv.end())
		{
			if (req) fail("missing " + k + "=");
			return def;
		}
		m_used.insert(k);
		return it->second;
	}
	double num(const std::string& k, double def, bool req = false)
	{
		if (!has(k))
		{
			if (req) fail("missing " + k + "=");
			return def;
		}
		return toNum(k, str(k));
	}
	double req(const std::string& k) { return num(k, 0, true); }
	double pos(const std::string& k, double def, bool required = false)
	{
		const double v = num(k, def, required);
		if (!(v > 0)) fail(k + " must be > 0");
		return v;
	}
	double toNum(const std::string& k, const std::string& s) const
	{
		if (s == "inf") return std::numeric_limits<double>::infinity();
		try
		{
			size_t n = 0;
			const double v = std::stod(s, &n);
			if (n != s.size() || !std::isfinite(v)) throw std::invalid_argument("x");
			return v;
		}
		catch (const std::exception&)
		{
			fail("bad number for " + k + ": '" + s + "'");
		}
	}
	std::vector<double> list(const std::string& k, size_t n, bool req = true)
	{
		if (!has(k))
		{
			if (req) fail("missing " + k + "=");
			return {};
		}
		const std::vector<double> v = numbers(k, str(k));
		if (v.size() != n) fail(k + " needs " + std::to_string(n) + " comma-separated numbers");
		return v;
	}
	/** The comma-separated numbers of `text`, a value of key `k` (named in the errors). */
	std::vector<double> numbers(const std::string& k, const std::string& text) const
	{
		std::vector<double> v;
		std::stringstream ss(text);
		std::string item;
		while (std::getline(ss, item, ',')) v.push_back(toNum(k, item));
		return v;
	}
	void finish() const
	{
		for (const auto& kv : m_kv)
			if (!m_used.count(kv.first)) fail("unknown key '" + kv.first + "'");
	}

   private:
	std::string m_kw, m_where;
	std::map<std::string, std::string> m_kv;
	std::set<std::string> m_used;
};

Pose3 poseOf(const std::vector<double>& v)
{
	return Pose3::fromXYZYPR(v[0], v[1], v[2], v[3] * kDeg, v[4] * kDeg, v[5] * kDeg);
}

/** Pose of a primitive's local frame: origin on the floor at (x,y,z), yawed. */
Pose3 planar(double x, double y, double z, double yawDeg) { return Pose3::fromXYZYPR(x, y, z, yawDeg * kDeg, 0, 0); }

/** Axis-aligned box in a local frame given by its min/max corners. */
ConvexSolid localBox(const Pose3& f, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int id)
{
	Pose3 c = f;
	c.t = f.apply(0.5 * (lo + hi));
	return ConvexSolid::box(c, 0.5 * (hi - lo), id);
}

}  // namespace

void applyCameraKeys(KinectParams& k, const std::map<std::string, double>& keys)
{
	auto set = [&](const char* key, double& v) {
		if (auto it = keys.find(key); it != keys.end()) v = it->second;
	};
	set("noise_scale", k.noise_scale);
	set("min_range", k.min_range);
	set("max_range", k.max_range);
	set("spike_prob", k.spike_prob);
	set("flying_prob", k.flying_prob);
	set("grazing_start", k.grazing_start_deg);
	set("grazing_end", k.grazing_end_deg);
}

void setCameraModel(SceneFile& sf, CameraModel model)
{
	const bool noise = sf.kinect.noise;
	sf.kinect = cameraPreset(model);
	applyCameraKeys(sf.kinect, sf.kinect_keys);
	sf.kinect.noise = noise;
	for (ExtraKinect& e : sf.more_kinects)
	{
		const bool n = e.params.noise;
		e.params = cameraPreset(model);
		applyCameraKeys(e.params, e.keys);
		e.params.noise = n;
	}
	// Labels that follow the model follow it here too, unless that would give two
	// cameras one label (the map keeps a pipeline and a mount per label).
	auto taken = [&](const std::string& l) {
		if (sf.kinect_label == l) return true;
		for (const ExtraKinect& e : sf.more_kinects)
			if (e.label == l) return true;
		return false;
	};
	const std::string label = defaultCameraLabel(model);
	if (!sf.kinect_label_given && !taken(label)) sf.kinect_label = label;
	for (ExtraKinect& e : sf.more_kinects)
		if (!e.label_given && !taken(label)) e.label = label;
}

namespace
{
/** What the statements build, line after line. */
struct SceneBuilder
{
	SceneFile sf;
	std::set<int> ids;  ///< object ids used so far
	bool havePath = false;
	std::set<std::string> kinectLabels;
};

/** "A-B" (frames A to B, inclusive) or "A-" (from A on); 0-based frame numbers. */
void frameRange(Args& a, const std::string& k, int& first, int& last)
{
	const std::string v = a.str(k);
	const auto dash = v.find('-');
	if (dash == std::string::npos || dash == 0) a.fail(k + "= wants A-B or A- (frame numbers, got '" + v + "')");
	const double f0 = a.toNum(k, v.substr(0, dash));
	const double f1 = dash + 1 < v.size() ? a.toNum(k, v.substr(dash + 1)) : 1e9;
	if (f0 < 0 || f0 != std::floor(f0) || f1 != std::floor(f1) || f1 < f0 || f1 > 1e9)
		a.fail(k + "= wants whole frame numbers 0 <= A <= B (got '" + v + "')");
	first = int(f0);
	last = f1 >= 1e9 ? std::numeric_limits<int>::max() : int(f1);
}

/** frames=A-B (present only then), move=dx,dy (per frame) or to=x,y (where x=,y= end
 * up), moving=A-B (when it moves; default the frames= range). Issue #14. */
void parseMotion(Args& a, ObjectInfo& oi)
{
	if (a.has("frames")) frameRange(a, "frames", oi.first_frame, oi.last_frame);
	if (a.has("moving") && !a.has("move") && !a.has("to")) a.fail("moving= needs move= or to=");
	if (!a.has("move") && !a.has("to")) return;
	if (a.has("move") && a.has("to")) a.fail("give move= or to=, not both");
	oi.move_first = oi.first_frame;
	oi.move_last = oi.last_frame;
	if (a.has("moving")) frameRange(a, "moving", oi.move_first, oi.move_last);
	if (a.has("move"))
	{
		const std::vector<double> m = a.list("move", 2);
		oi.move_per_frame = Eigen::Vector2d(m[0], m[1]);
		return;
	}
	if (!a.has("x") || !a.has("y")) a.fail("to= needs the object's x= and y= (use move=dx,dy per frame)");
	if (oi.move_last == std::numeric_limits<int>::max() || oi.move_last == oi.move_first)
		a.fail("to= needs a closed range of at least two frames in moving= or frames= (A-B, B > A)");
	const std::vector<double> t = a.list("to", 2);
	oi.move_per_frame =
		(Eigen::Vector2d(t[0], t[1]) - Eigen::Vector2d(a.req("x"), a.req("y"))) / double(oi.move_last - oi.move_first);
}

/** The keys every object takes (id=, name=, category=); adds the object to the scene. */
ObjectInfo& beginObject(SceneBuilder& b, Args& a, const std::string& type)
{
	const double idd = a.req("id");
	if (idd < 1 || idd != std::floor(idd) || idd > 1e9) a.fail("id must be an integer >= 1");
	const int id = int(idd);
	if (b.ids.count(id)) a.fail("duplicate id " + std::to_string(id));
	b.ids.insert(id);
	ObjectInfo oi;
	oi.id = id;
	oi.type = type;
	oi.name = a.str("name", type + "_" + std::to_string(id));
	if (a.has("category"))
	{
		if (!categoryFromName(a.str("category"), oi.category)) a.fail("unknown category '" + a.str("category") + "'");
		oi.category_given = true;
	}
	if (a.has("material"))
	{
		if (!materialFromName(a.str("material"), oi.material))
			a.fail("unknown material '" + a.str("material") + "' (normal, absorbing, transparent, specular)");
	}
	oi.dropout = a.num("dropout", oi.material == Material::Specular ? 0.5 : 0.0);
	if (!(oi.dropout >= 0 && oi.dropout <= 1)) a.fail("dropout must be in [0,1]");
	if (oi.dropout > 0 && oi.material != Material::Specular) a.fail("dropout= needs material=specular");
	parseMotion(a, oi);
	b.sf.scene.objects.push_back(oi);
	return b.sf.scene.objects.back();
}

/** Bounding box of the last object: the solids and holes from index firstSolid and
 * firstHole on (those its statement added). */
void finishObject(Scene& sc, size_t firstSolid, size_t firstHole)
{
	ObjectInfo* oi = &sc.objects.back();
	oi->bbox.setEmpty();
	for (size_t i = firstSolid; i < sc.solids.size(); i++) oi->bbox.extend(sc.solids[i].bbox);
	for (size_t i = firstHole; i < sc.holes.size(); i++)
	{
		const Hole& h = sc.holes[i];
		const double r = h.shape == Hole::Circle ? h.r : std::hypot(h.hx, h.hy);
		const double c = std::cos(h.yaw), s = std::sin(h.yaw);
		const double ex = h.shape == Hole::Circle ? r : std::abs(c * h.hx) + std::abs(s * h.hy);
		const double ey = h.shape == Hole::Circle ? r : std::abs(s * h.hx) + std::abs(c * h.hy);
		const double zb = std::isfinite(h.depth) ? -h.depth : -1e3;
		oi->bbox.extend(Eigen::Vector3d(h.cx - ex, h.cy - ey, zb));
		oi->bbox.extend(Eigen::Vector3d(h.cx + ex, h.cy + ey, 0));
	}
}

// One handler per statement: each reads its own arguments (and their defaults) from
// `a` into the scene; the keys it does not read are reported by Args::finish().

void parseFloor(SceneBuilder& b, Args& a) { b.sf.scene.has_floor = a.num("present", 1) != 0; }

void parseKinect(SceneBuilder& b, Args& a)
{
	SceneFile& sf = b.sf;
	CameraModel model = CameraModel::KinectOne;
	const std::string modelName = a.str("model", "kinect_one");
	if (!parseCameraModel(modelName, model))
		a.fail("unknown model '" + modelName + "' (known: " + cameraModelNames() + ")");
	const bool labelGiven = a.has("label");
	const std::string label = labelGiven ? a.str("label") : defaultCameraLabel(model);
	for (char c : label)
		if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-')
			a.fail("label must be letters, digits, _ or - (got '" + label + "')");
	if (b.kinectLabels.count(label)) a.fail("duplicate camera label '" + label + "'");
	b.kinectLabels.insert(label);
	// The first kinect statement sets the main camera (kinect, kinect_pose); each
	// further one adds a camera to more_kinects.
	const bool first = b.kinectLabels.size() == 1;
	ExtraKinect extra;
	if (first)
	{
		sf.kinect_label = label;
		sf.kinect_label_given = labelGiven;
	}
	extra.label = label;
	extra.label_given = labelGiven;
	Pose3& pose = first ? sf.kinect_pose : extra.pose;
	pose = poseOf(a.list("pose", 6));
	auto& k = first ? sf.kinect : extra.params;
	auto& keys = first ? sf.kinect_keys : extra.keys;
	for (const char* key :
		 {"noise_scale", "min_range", "max_range", "spike_prob", "flying_prob", "grazing_start", "grazing_end"})
		if (a.has(key)) keys[key] = a.num(key, 0);
	k = cameraPreset(model);
	applyCameraKeys(k, keys);
	if (k.noise_scale < 0) a.fail("noise_scale must be >= 0");
	if (!(k.min_range > 0) || !(k.max_range > 0)) a.fail("min_range and max_range must be > 0");
	if (k.max_range <= k.min_range) a.fail("max_range must be > min_range");
	if (k.spike_prob < 0 || k.spike_prob > 1 || k.flying_prob < 0 || k.flying_prob > 1)
		a.fail("probabilities must be in [0,1]");
	if (!(k.grazing_end_deg > k.grazing_start_deg)) a.fail("grazing_end must be > grazing_start");
	double& sway = first ? sf.kinect_sway : extra.sway;
	sway = a.num("sway", 0) * kDeg;
	if (sway < 0 || sway > 10 * kDeg) a.fail("sway must be in [0,10] degrees");
	if (!first) sf.more_kinects.push_back(extra);
}

void parseLeddar(SceneBuilder& b, Args& a)
{
	SceneFile& sf = b.sf;
	sf.leddar_pose = poseOf(a.list("pose", 6));
	sf.leddar_enabled = a.num("enabled", 1) != 0;
	sf.leddar.sigma = a.num("sigma", sf.leddar.sigma);
	if (sf.leddar.sigma < 0) a.fail("sigma must be >= 0");
	sf.leddar.max_range = a.pos("max_range", sf.leddar.max_range);
	sf.leddar.vfov_deg = a.pos("vfov", sf.leddar.vfov_deg);
}

void parseHole(SceneBuilder& b, Args& a)
{
	ObjectInfo& oi = beginObject(b, a, "hole");
	Hole h;
	h.object_id = oi.id;
	const std::string shape = a.str("shape", "rect");
	h.cx = a.req("x");
	h.cy = a.req("y");
	h.depth = a.pos("depth", 0, true);
	if (shape == "rect")
	{
		h.shape = Hole::Rect;
		h.hx = 0.5 * a.pos("sx", 0, true);
		h.hy = 0.5 * a.pos("sy", 0, true);
		h.yaw = a.num("yaw", 0) * kDeg;
	}
	else if (shape == "circle")
	{
		h.shape = Hole::Circle;
		h.r = a.pos("r", 0, true);
	}
	else
		a.fail("shape must be rect or circle");
	b.sf.scene.holes.push_back(h);
}

void parseFloorPatch(SceneBuilder& b, Args& a)
{
	ObjectInfo& oi = beginObject(b, a, "floor_patch");
	if (oi.material == Material::Transparent) a.fail("a floor patch cannot be transparent");
	if (!oi.category_given) oi.category = Category::None;  // still floor
	FloorPatch fp;
	fp.object_id = oi.id;
	fp.cx = a.req("x");
	fp.cy = a.req("y");
	fp.hx = 0.5 * a.pos("sx", 0, true);
	fp.hy = 0.5 * a.pos("sy", 0, true);
	fp.yaw = a.num("yaw", 0) * kDeg;
	oi.bbox = Eigen::AlignedBox3d(
		Eigen::Vector3d(fp.cx - std::hypot(fp.hx, fp.hy), fp.cy - std::hypot(fp.hx, fp.hy), 0),
		Eigen::Vector3d(fp.cx + std::hypot(fp.hx, fp.hy), fp.cy + std::hypot(fp.hx, fp.hy), 0));
	b.sf.scene.floor_patches.push_back(fp);
}

void parseBox(SceneBuilder& b, Args& a)
{
	ObjectInfo& oi = beginObject(b, a, "box");
	const double x = a.req("x"), y = a.req("y"), z = a.num("z", 0);
	const Eigen::Vector3d h(0.5 * a.pos("sx", 0, true), 0.5 * a.pos("sy", 0, true), 0.5 * a.pos("sz", 0, true));
	const double yaw = a.num("yaw", 0) * kDeg, pitch = a.num("pitch", 0) * kDeg, roll = a.num("roll", 0) * kDeg;
	// (x,y,z) = centre of the bottom face before pitch/roll
	Pose3 base = Pose3::fromXYZYPR(x, y, z, yaw, pitch, roll);
	Pose3 c = base;
	c.t = base.apply(Eigen::Vector3d(0, 0, h.z()));
	b.sf.scene.solids.push_back(ConvexSolid::box(c, h, oi.id));
}

void parseWall(SceneBuilder& b, Args& a)
{
	ObjectInfo& oi = beginObject(b, a, "wall");
	const double x0 = a.req("x0"), y0 = a.req("y0"), x1 = a.req("x1"), y1 = a.req("y1");
	const double th = a.pos("thickness", 0.10), hgt = a.pos("height", 2.5);
	const double len = std::hypot(x1 - x0, y1 - y0);
	if (len <= 0) a.fail("zero-length wall");
	const double yaw = std::atan2(y1 - y0, x1 - x0);
	Pose3 c = Pose3::fromXYZYPR(0.5 * (x0 + x1), 0.5 * (y0 + y1), 0.5 * hgt, yaw, 0, 0);
	b.sf.scene.solids.push_back(ConvexSolid::box(c, Eigen::Vector3d(0.5 * len, 0.5 * th, 0.5 * hgt), oi.id));
}

/** The arguments stairs_down and stairs_up share (x= y= yaw= width= rise= run= steps=). */
struct Stairs
{
	int id = 0;
	double yaw = 0, w = 0, rise = 0, run = 0;
	int steps = 0;
	Pose3 f;  ///< local frame: x along the stairs, origin at (x,y) on the floor
};

Stairs beginStairs(SceneBuilder& b, Args& a)
{
	Stairs s;
	s.id = beginObject(b, a, a.keyword()).id;
	const double x = a.req("x"), y = a.req("y"), yaw = a.num("yaw", 0);
	const double w = a.pos("width", 0, true), rise = a.pos("rise", 0, true), run = a.pos("run", 0, true);
	const double stepsD = a.req("steps");
	if (stepsD < 1 || stepsD != std::floor(stepsD) || stepsD > 100) a.fail("steps must be an integer in 1..100");
	s.yaw = yaw;
	s.w = w;
	s.rise = rise;
	s.run = run;
	s.steps = int(stepsD);
	s.f = planar(x, y, 0, yaw);
	return s;
}

void parseStairsDown(SceneBuilder& b, Args& a)
{
	const Stairs s = beginStairs(b, a);
	const double landing = a.pos("landing", 1.0);
	const double L = s.steps * s.run + landing, D = s.steps * s.rise;
	Hole h;
	h.shape = Hole::Rect;
	const Eigen::Vector3d c = s.f.apply(Eigen::Vector3d(0.5 * L, 0, 0));
	h.cx = c.x();
	h.cy = c.y();
	h.hx = 0.5 * L;
	h.hy = 0.5 * s.w;
	h.yaw = s.yaw * kDeg;
	h.depth = D;
	h.object_id = s.id;
	b.sf.scene.holes.push_back(h);
	// tread k (1..steps-1) at z = -k*rise over x in [(k-1)run, k run]
	for (int k = 1; k < s.steps; k++)
		b.sf.scene.solids.push_back(localBox(
			s.f, Eigen::Vector3d((k - 1) * s.run, -0.5 * s.w, -D), Eigen::Vector3d(k * s.run, 0.5 * s.w, -k * s.rise),
			s.id));
}

void parseStairsUp(SceneBuilder& b, Args& a)
{
	const Stairs s = beginStairs(b, a);
	const double top = a.pos("top", 1.0);
	const double L = s.steps * s.run + top;
	for (int k = 1; k <= s.steps; k++)
		b.sf.scene.solids.push_back(localBox(
			s.f, Eigen::Vector3d((k - 1) * s.run, -0.5 * s.w, 0), Eigen::Vector3d(L, 0.5 * s.w, k * s.rise), s.id));
}

void parseRamp(SceneBuilder& b, Args& a)
{
	Scene& sc = b.sf.scene;
	ObjectInfo& oi = beginObject(b, a, "ramp");
	const double x = a.req("x"), y = a.req("y"), yaw = a.num("yaw", 0);
	const double L = a.pos("length", 0, true), w = a.pos("width", 0, true);
	const double ang = a.pos("angle", 0, true);
	if (ang >= 60) a.fail("angle must be < 60 degrees");
	oi.slope_deg = ang;
	const std::string sides = a.str("sides", "solid");
	const double th = a.pos("thickness", 0.03);
	const double plateau = a.num("plateau", 0);
	const bool back = a.num("back", 0) != 0;
	if (plateau < 0) a.fail("plateau must be >= 0");
	const double H = L * std::tan(ang * kDeg);
	const Pose3 f = planar(x, y, 0, yaw);
	auto addSlope = [&](const Pose3& fr) {
		if (sides == "solid")
			sc.solids.push_back(ConvexSolid::wedge(fr, L, w, ang * kDeg, oi.id));
		else if (sides == "open")
		{
			// tilted plate: its top surface is the ramp surface
			const double hyp = L / std::cos(ang * kDeg);
			Pose3 tilt = fr * Pose3::fromXYZYPR(0, 0, 0, 0, -ang * kDeg, 0);
			Pose3 c = tilt;
			c.t = tilt.apply(Eigen::Vector3d(0.5 * hyp, 0, -0.5 * th));
			sc.solids.push_back(ConvexSolid::box(c, Eigen::Vector3d(0.5 * hyp, 0.5 * w, 0.5 * th), oi.id));
		}
		else
			a.fail("sides must be solid or open");
	};
	addSlope(f);
	if (plateau > 0)
		sc.solids.push_back(localBox(
			f, Eigen::Vector3d(L, -0.5 * w, sides == "solid" ? 0.0 : H - th), Eigen::Vector3d(L + plateau, 0.5 * w, H),
			oi.id));
	if (back) addSlope(f * planar(2 * L + plateau, 0, 0, 180.0));
}

void parseTable(SceneBuilder& b, Args& a)
{
	Scene& sc = b.sf.scene;
	ObjectInfo& oi = beginObject(b, a, "table");
	const Pose3 f = planar(a.req("x"), a.req("y"), 0, a.num("yaw", 0));
	const double sx = a.pos("sx", 0, true), sy = a.pos("sy", 0, true);
	const double H = a.pos("height", 0.75), top = a.pos("top", 0.04), leg = a.pos("leg", 0.05);
	if (top >= H || 2 * leg >= std::min(sx, sy)) a.fail("inconsistent table sizes");
	sc.solids.push_back(
		localBox(f, Eigen::Vector3d(-0.5 * sx, -0.5 * sy, H - top), Eigen::Vector3d(0.5 * sx, 0.5 * sy, H), oi.id));
	for (int i = 0; i < 4; i++)
	{
		const double lx = (i & 1) ? 0.5 * sx - leg : -0.5 * sx;
		const double ly = (i & 2) ? 0.5 * sy - leg : -0.5 * sy;
		sc.solids.push_back(
			localBox(f, Eigen::Vector3d(lx, ly, 0), Eigen::Vector3d(lx + leg, ly + leg, H - top), oi.id));
	}
}

void parseShelf(SceneBuilder& b, Args& a)
{
	Scene& sc = b.sf.scene;
	ObjectInfo& oi = beginObject(b, a, "shelf");
	const Pose3 f = planar(a.req("x"), a.req("y"), 0, a.num("yaw", 0));
	const double sx = a.pos("sx", 0, true), sy = a.pos("sy", 0, true), sz = a.pos("sz", 0, true);
	const double nb = a.num("boards", 4), bt = a.pos("board", 0.02), side = a.pos("side", 0.02);
	const double bottom = a.num("bottom", 0.10);
	if (nb < 1 || nb != std::floor(nb) || nb > 50) a.fail("boards must be an integer in 1..50");
	if (bottom < 0 || bottom + bt > sz || 2 * side >= sx) a.fail("inconsistent shelf sizes");
	// sides at local x = +-sx/2 (the shelf's length runs along local x)
	for (int s = -1; s <= 1; s += 2)
	{
		const double x0 = s < 0 ? -0.5 * sx : 0.5 * sx - side;
		sc.solids.push_back(
			localBox(f, Eigen::Vector3d(x0, -0.5 * sy, 0), Eigen::Vector3d(x0 + side, 0.5 * sy, sz), oi.id));
	}
	const int n = int(nb);
	for (int k = 0; k < n; k++)
	{
		const double z = n == 1 ? bottom : bottom + k * (sz - bt - bottom) / (n - 1);
		sc.solids.push_back(localBox(
			f, Eigen::Vector3d(-0.5 * sx + side, -0.5 * sy, z), Eigen::Vector3d(0.5 * sx - side, 0.5 * sy, z + bt),
			oi.id));
	}
}

void parsePath(SceneBuilder& b, Args& a)
{
	if (b.havePath) a.fail("only one path allowed");
	b.havePath = true;
	PathSpec& p = b.sf.path;
	std::stringstream ws(a.str("waypoints", "", true));
	std::string wp;
	while (std::getline(ws, wp, ';'))
	{
		const std::vector<double> v = a.numbers("waypoints", wp);
		if (v.size() != 3) a.fail("each waypoint needs x,y,yaw (got '" + wp + "')");
		p.waypoints.push_back({v[0], v[1], v[2] * kDeg});
	}
	if (p.waypoints.empty()) a.fail("no waypoints");
	p.spacing = a.pos("spacing", p.spacing);
	p.turn_spacing = a.pos("turn_spacing", p.turn_spacing / kDeg) * kDeg;
	const double fr = a.num("frames", 0);
	if (fr < 0 || fr != std::floor(fr) || fr > 1e6) a.fail("frames must be an integer >= 0");
	p.frames = int(fr);
	p.rate_hz = a.pos("rate", p.rate_hz);
}

void parseOdometryNoise(SceneBuilder& b, Args& a)
{
	auto& o = b.sf.odometry_noise;
	o.xy_per_m = a.num("xy", 0);
	o.yaw_per_m = a.num("yaw", 0) * kDeg;
	o.yaw_per_rad = a.num("turn", 0);
	if (o.xy_per_m < 0 || o.yaw_per_m < 0 || o.yaw_per_rad < 0) a.fail("noise must be >= 0");
	o.scale = a.num("scale", 0);
	if (std::abs(o.scale) >= 0.5) a.fail("scale must be in (-0.5, 0.5)");
	o.yaw_bias_per_m = a.num("yaw_bias", 0) * kDeg;
	if (std::abs(o.yaw_bias_per_m) > 90 * kDeg) a.fail("yaw_bias must be in [-90, 90] degrees per metre");
}

void parseGrid(SceneBuilder& b, Args& a)
{
	GridSpec& g = b.sf.grid;
	g.resolution = a.pos("resolution", g.resolution);
	g.min_x = a.req("min_x");
	g.max_x = a.req("max_x");
	g.min_y = a.req("min_y");
	g.max_y = a.req("max_y");
	if (g.max_x <= g.min_x || g.max_y <= g.min_y) a.fail("empty grid extent");
	if ((g.max_x - g.min_x) / g.resolution * (g.max_y - g.min_y) / g.resolution > 5e7) a.fail("grid too large");
	g.robot_height = a.pos("robot_height", g.robot_height);
	g.obstacle_min_height = a.pos("obstacle_min", g.obstacle_min_height);
	g.drop_min_depth = a.pos("drop_min", g.drop_min_depth);
	g.small_max_height = a.pos("small_max", g.small_max_height);
	g.overhang_clearance = a.pos("overhang_clearance", g.overhang_clearance);
	g.max_slope_deg = a.pos("max_slope", g.max_slope_deg);
	const double ss = a.num("subsamples", g.subsamples);
	if (ss < 1 || ss > 9 || ss != std::floor(ss)) a.fail("subsamples must be an integer in 1..9");
	g.subsamples = int(ss);
	if (a.has("per_frame")) b.sf.per_frame_truth = a.num("per_frame", 0) != 0 ? 1 : 0;
	b.sf.has_grid = true;
}

/** A scene file is one statement per line: a keyword and its key=value arguments
 * ('#' starts a comment; the format is in SceneFile.h, examples in config/scenes/).
 * This table gives the handler of each keyword. */
struct Statement
{
	const char* keyword;
	void (*parse)(SceneBuilder& b, Args& a);
};
constexpr Statement kStatements[] = {
	{"floor", parseFloor},
	{"kinect", parseKinect},
	{"leddar", parseLeddar},
	{"hole", parseHole},
	{"box", parseBox},
	{"floor_patch", parseFloorPatch},
	{"wall", parseWall},
	{"stairs_down", parseStairsDown},
	{"stairs_up", parseStairsUp},
	{"ramp", parseRamp},
	{"table", parseTable},
	{"shelf", parseShelf},
	{"path", parsePath},
	{"odometry_noise", parseOdometryNoise},
	{"grid", parseGrid},
};

const Statement* findStatement(const std::string& kw)
{
	for (const Statement& s : kStatements)
		if (kw == s.keyword) return &s;
	return nullptr;
}
}  // namespace

SceneFile parseScene(std::istream& in, const std::string& filename)
{
	SceneBuilder b;
	Scene& sc = b.sf.scene;
	std::string line;
	int lineNo = 0;
	while (std::getline(in, line))
	{
		lineNo++;
		const auto hash = line.find('#');
		if (hash != std::string::npos) line.resize(hash);
		std::stringstream ss(line);
		std::string kw, tok;
		if (!(ss >> kw)) continue;
		const std::string where = filename + ":" + std::to_string(lineNo);
		Args a(kw, where);
		while (ss >> tok) a.add(tok);

		const Statement* st = findStatement(kw);
		if (!st) throw SceneError(where + ": unknown statement '" + kw + "'");
		const size_t s0 = sc.solids.size(), h0 = sc.holes.size();
		st->parse(b, a);
		if (!sc.objects.empty() && sc.solids.size() + sc.holes.size() != s0 + h0)
		{
			finishObject(sc, s0, h0);
			// The parts of a transparent object let the light through.
			if (sc.objects.back().material == Material::Transparent)
				for (size_t i = s0; i < sc.solids.size(); i++) sc.solids[i].transparent = true;
			if (sc.objects.back().material == Material::Transparent && sc.holes.size() != h0)
				throw SceneError(where + ": a hole cannot be transparent");
		}
		a.finish();
	}
	SceneFile& sf = b.sf;
	if (!b.havePath) throw SceneError(filename + ": no 'path' statement");
	if (!sf.has_grid)
	{
		// default: around the path, as far as the Kinect sees, plus all objects
		Eigen::AlignedBox2d box;
		box.setEmpty();
		for (const auto& w : sf.path.waypoints) box.extend(Eigen::Vector2d(w.x, w.y));
		const double m = sf.kinect.max_range + 0.5;
		box.min() -= Eigen::Vector2d(m, m);
		box.max() += Eigen::Vector2d(m, m);
		sf.grid.min_x = std::floor(box.min().x());
		sf.grid.min_y = std::floor(box.min().y());
		sf.grid.max_x = std::ceil(box.max().x());
		sf.grid.max_y = std::ceil(box.max().y());
	}
	return std::move(b.sf);
}

SceneFile parseSceneFile(const std::string& path)
{
	std::ifstream f(path);
	if (!f) throw SceneError(path + ": cannot open file");
	return parseScene(f, path);
}

}  // namespace gam::sim
