// Ground-aware mapping for MRPT -- scene simulator: geometry and ray casting.
#include "gam/sim/Scene.h"

#include <algorithm>
#include <cmath>

namespace gam::sim
{
const char* categoryName(Category c)
{
	switch (c)
	{
		case Category::None: return "none";
		case Category::Negative: return "negative";
		case Category::Small: return "small";
		case Category::Overhang: return "overhang";
		case Category::Large: return "large";
		case Category::Ramp: return "ramp";
	}
	return "?";
}

bool categoryFromName(const std::string& s, Category& c)
{
	for (int i = 0; i <= 5; i++)
		if (s == categoryName(Category(i)))
		{
			c = Category(i);
			return true;
		}
	return false;
}

const char* materialName(Material m)
{
	switch (m)
	{
		case Material::Normal: return "normal";
		case Material::Absorbing: return "absorbing";
		case Material::Transparent: return "transparent";
		case Material::Specular: return "specular";
	}
	return "?";
}

bool materialFromName(const std::string& s, Material& m)
{
	for (int i = 0; i <= 3; i++)
		if (s == materialName(Material(i)))
		{
			m = Material(i);
			return true;
		}
	return false;
}

bool FloorPatch::containsXY(double x, double y) const
{
	const double c = std::cos(yaw), s = std::sin(yaw);
	const double dx = x - cx, dy = y - cy;
	const double lx = c * dx + s * dy, ly = -s * dx + c * dy;
	return std::abs(lx) <= hx && std::abs(ly) <= hy;
}

Pose3 Pose3::fromXYZYPR(double x, double y, double z, double yaw, double pitch, double roll)
{
	Pose3 p;
	p.R = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
		   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
			  .toRotationMatrix();
	p.t = Eigen::Vector3d(x, y, z);
	return p;
}

Pose3 Pose3::operator*(const Pose3& o) const
{
	Pose3 r;
	r.R = R * o.R;
	r.t = R * o.t + t;
	return r;
}

Eigen::Vector3d Pose3::ypr() const
{
	const double yaw = std::atan2(R(1, 0), R(0, 0));
	const double pitch = std::atan2(-R(2, 0), std::hypot(R(0, 0), R(1, 0)));
	const double roll = std::atan2(R(2, 1), R(2, 2));
	return {yaw, pitch, roll};
}

// ---------------------------------------------------------------- ConvexSolid
void ConvexSolid::addPlane(const Eigen::Vector3d& normal, const Eigen::Vector3d& p)
{
	const Eigen::Vector3d u = normal.normalized();
	n.push_back(u);
	d.push_back(u.dot(p));
}

ConvexSolid ConvexSolid::box(const Pose3& c, const Eigen::Vector3d& h, int id)
{
	ConvexSolid s;
	s.object_id = id;
	for (int a = 0; a < 3; a++)
		for (int sg = -1; sg <= 1; sg += 2)
		{
			const Eigen::Vector3d nl = Eigen::Vector3d::Unit(a) * sg;
			s.addPlane(c.R * nl, c.apply(nl * h[a]));
		}
	s.bbox.setEmpty();
	for (int i = 0; i < 8; i++)
	{
		Eigen::Vector3d v((i & 1) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 4) ? h.z() : -h.z());
		s.bbox.extend(c.apply(v));
	}
	return s;
}

ConvexSolid ConvexSolid::wedge(const Pose3& o, double length, double width, double angle, int id)
{
	ConvexSolid s;
	s.object_id = id;
	const double H = length * std::tan(angle);
	const double hw = 0.5 * width;
	// bottom, far end, two sides, sloped top
	s.addPlane(o.R * Eigen::Vector3d(0, 0, -1), o.apply({0, 0, 0}));
	s.addPlane(o.R * Eigen::Vector3d(1, 0, 0), o.apply({length, 0, 0}));
	s.addPlane(o.R * Eigen::Vector3d(0, 1, 0), o.apply({0, hw, 0}));
	s.addPlane(o.R * Eigen::Vector3d(0, -1, 0), o.apply({0, -hw, 0}));
	s.addPlane(o.R * Eigen::Vector3d(-std::sin(angle), 0, std::cos(angle)), o.apply({0, 0, 0}));
	s.bbox.setEmpty();
	for (double x : {0.0, length})
		for (double y : {-hw, hw})
			for (double z : {0.0, H}) s.bbox.extend(o.apply({x, y, z}));
	return s;
}

bool ConvexSolid::contains(const Eigen::Vector3d& p, double eps) const
{
	for (size_t i = 0; i < n.size(); i++)
		if (n[i].dot(p) > d[i] + eps) return false;
	return true;
}

bool ConvexSolid::intersect(
	const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, double tmax, double& t,
	Eigen::Vector3d& normal) const
{
	double tin = tmin, tout = tmax;
	int inPlane = -1;
	for (size_t i = 0; i < n.size(); i++)
	{
		const double den = n[i].dot(dir);
		const double dist = d[i] - n[i].dot(o);  // >= 0 if o is inside this half-space
		if (std::abs(den) < 1e-15)
		{
			if (dist < 0) return false;
			continue;
		}
		const double ti = dist / den;
		if (den < 0)
		{
			if (ti > tin)
			{
				tin = ti;
				inPlane = int(i);
			}
		}
		else if (ti < tout)
			tout = ti;
		if (tin > tout) return false;
	}
	if (inPlane < 0) return false;  // started inside (or tangent)
	t = tin;
	normal = n[size_t(inPlane)];
	return true;
}

bool ConvexSolid::verticalExtent(double x, double y, double& zmin, double& zmax) const
{
	double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
	const Eigen::Vector3d o(x, y, 0.0);
	for (size_t i = 0; i < n.size(); i++)
	{
		const double den = n[i].z();
		const double dist = d[i] - n[i].dot(o);
		if (std::abs(den) < 1e-12)
		{
			if (dist < 0) return false;
			continue;
		}
		const double ti = dist / den;
		if (den < 0)
			lo = std::max(lo, ti);
		else
			hi = std::min(hi, ti);
	}
	if (lo > hi) return false;
	zmin = lo;
	zmax = hi;
	return true;
}

// ----------------------------------------------------------------------- Hole
bool Hole::containsXY(double x, double y) const
{
	const double dx = x - cx, dy = y - cy;
	if (shape == Circle) return dx * dx + dy * dy < r * r;
	const double c = std::cos(yaw), s = std::sin(yaw);
	const double lx = c * dx + s * dy, ly = -s * dx + c * dy;
	return std::abs(lx) < hx && std::abs(ly) < hy;
}

double Hole::exitT(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, Eigen::Vector3d& normal) const
{
	const double inf = std::numeric_limits<double>::infinity();
	double best = inf;
	Eigen::Vector3d nb = Eigen::Vector3d::Zero();
	// top (open: leaving upwards means back into the air) and bottom
	if (dir.z() > 0)
	{
		const double t = -o.z() / dir.z();
		if (t > tmin && t < best)
		{
			best = t;
			nb.setZero();  // marks "left through the top"
		}
	}
	else if (dir.z() < 0 && std::isfinite(depth))
	{
		const double t = (-depth - o.z()) / dir.z();
		if (t > tmin && t < best)
		{
			best = t;
			nb = Eigen::Vector3d::UnitZ();
		}
	}
	const double dx = o.x() - cx, dy = o.y() - cy;
	if (shape == Rect)
	{
		const double c = std::cos(yaw), s = std::sin(yaw);
		const double lx = c * dx + s * dy, ly = -s * dx + c * dy;
		const double ldx = c * dir.x() + s * dir.y(), ldy = -s * dir.x() + c * dir.y();
		const Eigen::Vector3d ex(c, s, 0), ey(-s, c, 0);
		if (std::abs(ldx) > 1e-15)
		{
			const double t = ((ldx > 0 ? hx : -hx) - lx) / ldx;
			if (t > tmin && t < best)
			{
				best = t;
				nb = ldx > 0 ? Eigen::Vector3d(-ex) : ex;
			}
		}
		if (std::abs(ldy) > 1e-15)
		{
			const double t = ((ldy > 0 ? hy : -hy) - ly) / ldy;
			if (t > tmin && t < best)
			{
				best = t;
				nb = ldy > 0 ? Eigen::Vector3d(-ey) : ey;
			}
		}
	}
	else
	{
		const double a = dir.x() * dir.x() + dir.y() * dir.y();
		if (a > 1e-30)
		{
			const double b = 2 * (dx * dir.x() + dy * dir.y());
			const double cc = dx * dx + dy * dy - r * r;
			const double disc = b * b - 4 * a * cc;
			if (disc >= 0)
			{
				const double t = (-b + std::sqrt(disc)) / (2 * a);
				if (t > tmin && t < best)
				{
					best = t;
					const Eigen::Vector3d p = o + t * dir;
					nb = Eigen::Vector3d(cx - p.x(), cy - p.y(), 0).normalized();
				}
			}
		}
	}
	normal = nb;
	return best;
}

// ---------------------------------------------------------------------- Scene
bool Scene::castGround(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, double tmax, RayHit& h) const
{
	if (!has_floor) return false;
	const double eps = 1e-9 / std::max(1e-12, dir.norm());
	double t;
	Eigen::Vector3d nrm = Eigen::Vector3d::UnitZ();
	const double z0 = o.z() + tmin * dir.z();
	if (z0 > 0)
	{
		if (dir.z() >= 0) return false;
		t = -o.z() / dir.z();
	}
	else
	{
		t = tmin;
		const Eigen::Vector3d p0 = o + (tmin + eps) * dir;
		bool inPit = false;
		for (const auto& hl : holes) inPit = inPit || hl.containsXYZ(p0);
		if (!inPit) return false;  // starts inside the floor
	}
	int hitObj = 0;
	for (int iter = 0; iter < 64; iter++)
	{
		if (t > tmax) return false;
		const Eigen::Vector3d pe = o + (t + eps) * dir;
		const Hole* in = nullptr;
		for (const auto& hl : holes)
			if (hl.containsXYZ(pe))
			{
				in = &hl;
				break;
			}
		if (!in)
		{
			h.hit = true;
			h.t = t;
			h.point = o + t * dir;
			h.normal = nrm;
			h.object_id = hitObj;
			if (hitObj == 0)
				for (const auto& fp : floor_patches)
					if (fp.containsXY(h.point.x(), h.point.y()))
					{
						h.object_id = fp.object_id;
						break;
					}
			return true;
		}
		Eigen::Vector3d n2;
		const double te = in->exitT(o, dir, t, n2);
		if (!std::isfinite(te)) return false;
		if (n2.squaredNorm() == 0) return false;  // back out through the top
		t = te;
		nrm = n2;
		hitObj = in->object_id;
	}
	return false;
}

RayHit Scene::cast(const Eigen::Vector3d& o, const Eigen::Vector3d& dir, double tmin, double tmax) const
{
	RayHit best;
	if (castGround(o, dir, tmin, tmax, best)) tmax = best.t;
	const Eigen::Vector3d inv(1.0 / dir.x(), 1.0 / dir.y(), 1.0 / dir.z());
	for (const auto& s : solids)
	{
		if (s.transparent) continue;  // clear glass / plastic: the light passes
		// slab test against the bounding box first
		double t0 = tmin, t1 = tmax;
		bool miss = false;
		for (int a = 0; a < 3 && !miss; a++)
		{
			if (dir[a] == 0)
			{
				if (o[a] < s.bbox.min()[a] || o[a] > s.bbox.max()[a]) miss = true;
				continue;
			}
			double ta = (s.bbox.min()[a] - o[a]) * inv[a], tb = (s.bbox.max()[a] - o[a]) * inv[a];
			if (ta > tb) std::swap(ta, tb);
			t0 = std::max(t0, ta);
			t1 = std::min(t1, tb);
			if (t0 > t1 + 1e-12) miss = true;
		}
		if (miss) continue;
		double t;
		Eigen::Vector3d nrm;
		if (s.intersect(o, dir, tmin, tmax, t, nrm) && t < tmax)
		{
			tmax = t;
			best.hit = true;
			best.t = t;
			best.point = o + t * dir;
			best.normal = nrm;
			best.object_id = s.object_id;
		}
	}
	return best;
}

bool Scene::insideMatter(const Eigen::Vector3d& p) const
{
	if (has_floor && p.z() <= 0)
	{
		bool inHole = false;
		for (const auto& h : holes)
			if (h.containsXYZ(p))
			{
				inHole = true;
				break;
			}
		if (!inHole) return true;
	}
	for (const auto& s : solids)
		if (s.contains(p)) return true;
	return false;
}

const ObjectInfo* Scene::object(int id) const
{
	for (const auto& o : objects)
		if (o.id == id) return &o;
	return nullptr;
}

Material Scene::materialOf(int id) const
{
	if (id == 0) return Material::Normal;
	const ObjectInfo* o = object(id);
	return o ? o->material : Material::Normal;
}

Eigen::AlignedBox3d Scene::bounds() const
{
	Eigen::AlignedBox3d b;
	b.setEmpty();
	for (const auto& s : solids) b.extend(s.bbox);
	for (const auto& h : holes)
	{
		const double r = h.shape == Hole::Circle ? h.r : std::hypot(h.hx, h.hy);
		const double zb = std::isfinite(h.depth) ? -h.depth : -10.0;
		b.extend(Eigen::Vector3d(h.cx - r, h.cy - r, zb));
		b.extend(Eigen::Vector3d(h.cx + r, h.cy + r, 0));
	}
	return b;
}

bool Scene::dynamic() const
{
	for (const auto& o : objects)
		if (o.dynamic()) return true;
	return false;
}

Scene Scene::atFrame(int frame) const
{
	Scene s;
	s.has_floor = has_floor;
	s.objects = objects;
	if (!dynamic())
	{
		s.holes = holes;
		s.solids = solids;
		s.floor_patches = floor_patches;
		return s;
	}
	// per object id: present? offset?
	auto state = [&](int id, Eigen::Vector2d& off) {
		const ObjectInfo* o = object(id);
		off = o ? o->offsetAt(frame) : Eigen::Vector2d::Zero();
		return !o || o->presentAt(frame);
	};
	Eigen::Vector2d off;
	for (const auto& h : holes)
		if (state(h.object_id, off))
		{
			Hole c = h;
			c.cx += off.x();
			c.cy += off.y();
			s.holes.push_back(c);
		}
	for (const auto& p : floor_patches)
		if (state(p.object_id, off))
		{
			FloorPatch c = p;
			c.cx += off.x();
			c.cy += off.y();
			s.floor_patches.push_back(c);
		}
	for (const auto& so : solids)
		if (state(so.object_id, off))
		{
			ConvexSolid c = so;
			const Eigen::Vector3d t(off.x(), off.y(), 0);
			for (size_t i = 0; i < c.n.size(); i++) c.d[i] += c.n[i].dot(t);  // n.(p - t) <= d
			c.bbox.translate(t);
			s.solids.push_back(c);
		}
	return s;
}

Eigen::AlignedBox2d Scene::footprintAt(int id, int frame) const
{
	Eigen::AlignedBox2d b;
	b.setEmpty();
	const ObjectInfo* o = object(id);
	if (!o || !o->presentAt(frame) || o->bbox.isEmpty()) return b;
	const Eigen::Vector2d off = o->offsetAt(frame);
	b.extend(o->bbox.min().head<2>() + off);
	b.extend(o->bbox.max().head<2>() + off);
	return b;
}

}  // namespace gam::sim
