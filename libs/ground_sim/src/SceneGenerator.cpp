// Ground-aware mapping for MRPT -- scene simulator: seeded scene generator.
#include "gam/sim/SceneGenerator.h"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <fstream>
#include <functional>
#include <limits>
#include <queue>
#include <random>
#include <sstream>
#include <stdexcept>

namespace gam::sim
{
const char* hazardKindName(HazardKind k)
{
	switch (k)
	{
		case HazardKind::Hole: return "hole";
		case HazardKind::Outlet: return "outlet";
		case HazardKind::StepDown: return "step_down";
		case HazardKind::Stairwell: return "stairwell";
		case HazardKind::CableProtector: return "cable_protector";
		case HazardKind::SmallBox: return "small_box";
		case HazardKind::Table: return "table";
		case HazardKind::Ramp: return "ramp";
		case HazardKind::Person: return "person";
	}
	return "?";
}

namespace
{
constexpr double kDeg = M_PI / 180;

/** Uniform numbers from the mt19937 stream itself (the standard distributions
 * may differ between standard libraries; the scenes must not). */
struct Rand
{
	std::mt19937 g;
	explicit Rand(unsigned seed) : g(seed) {}
	double u(double a, double b) { return a + (b - a) * (double(g()) / 4294967296.0); }
	int i(int n) { return int(g() % unsigned(n)); }
	bool coin(double p = 0.5) { return u(0, 1) < p; }
};

std::string fmt(const char* f, ...) __attribute__((format(printf, 1, 2)));
std::string fmt(const char* f, ...)
{
	char b[512];
	va_list ap;
	va_start(ap, f);
	std::vsnprintf(b, sizeof b, f, ap);
	va_end(ap);
	return b;
}

double snap(double v, double step) { return std::round(v / step) * step; }

/** One candidate layout, as scene-file statements. */
struct Layout
{
	std::vector<std::string> lines;
	std::vector<GeneratedHazard> hazards;
	std::vector<int> walls;
	std::vector<Eigen::AlignedBox2d> taken;  ///< hazard footprints grown by a margin
	Eigen::Vector2d start, goal;
	int nextId = 1;
	HazardKind lineKind = HazardKind::Hole;
	int lineId = 0;
	bool ok = true;  ///< false: a passage of the line hazard is a trap (below)
	bool clear(const Eigen::AlignedBox2d& b) const
	{
		for (const auto& t : taken)
			if (t.intersects(b)) return false;
		return true;
	}
};

Eigen::AlignedBox2d boxAround(double cx, double cy, double rx, double ry)
{
	return Eigen::AlignedBox2d(Eigen::Vector2d(cx - rx, cy - ry), Eigen::Vector2d(cx + rx, cy + ry));
}

/** The corridor: walls along +x at y = +-W/2, optionally widened into a room
 * between x = a and x = b on one or both sides. yTop/yBot: the walls' y at x. */
struct Corridor
{
	double W = 3, L = 6, x0 = -1.0, x1 = 7;
	bool room = false;
	double a = 0, b = 0, eTop = 0, eBot = 0;
	double yTop(double x) const { return W / 2 + (room && x > a && x < b ? eTop : 0); }
	double yBot(double x) const { return -W / 2 - (room && x > a && x < b ? eBot : 0); }
};

void addWall(Layout& lay, const char* name, double xa, double ya, double xb, double yb)
{
	const int id = lay.nextId++;
	lay.walls.push_back(id);
	lay.lines.push_back(
		fmt("wall id=%d name=%s x0=%.3f y0=%.3f x1=%.3f y1=%.3f thickness=0.10 height=2.5", id, name, xa, ya, xb, yb));
}

int addHazard(Layout& lay, HazardKind k, bool onLine, const std::string& statement)
{
	const int id = lay.nextId++;
	GeneratedHazard h;
	h.kind = k;
	h.objectId = id;
	h.onLine = onLine;
	lay.hazards.push_back(h);
	// statement has "%ID%" where the id goes
	std::string s = statement;
	const auto p = s.find("%ID%");
	s.replace(p, 4, std::to_string(id));
	lay.lines.push_back(s);
	return id;
}

/** A hazard of kind k centred on (cx, cy), free-standing (not one of the
 * kinds that need a wall): its statement and footprint half size. */
std::string freeHazard(Rand& r, HazardKind k, double cx, double cy, Eigen::Vector2d& half)
{
	// half sizes of the axis-aligned box around a sx x sy rectangle turned by yaw [deg]
	auto aabb = [&](double sx, double sy, double yawDeg) {
		const double c = std::abs(std::cos(yawDeg * kDeg)), s = std::abs(std::sin(yawDeg * kDeg));
		half = Eigen::Vector2d(c * sx / 2 + s * sy / 2, s * sx / 2 + c * sy / 2);
	};
	switch (k)
	{
		case HazardKind::Hole: {
			const double sx = r.u(0.4, 0.8), sy = r.u(0.4, 0.8), yaw = r.u(-30, 30), d = r.u(0.2, 0.6);
			aabb(sx, sy, yaw);
			return fmt(
				"hole id=%%ID%% name=hole shape=rect x=%.3f y=%.3f sx=%.3f sy=%.3f yaw=%.1f depth=%.3f", cx, cy, sx, sy,
				yaw, d);
		}
		case HazardKind::Outlet: {
			const double sx = r.u(0.08, 0.25), sy = r.u(0.08, 0.20), yaw = r.u(-45, 45), d = r.u(0.05, 0.10);
			aabb(sx, sy, yaw);
			if (r.coin(0.3))
			{
				const double rr = r.u(0.05, 0.10);
				half = Eigen::Vector2d(rr, rr);
				return fmt(
					"hole id=%%ID%% name=round_outlet shape=circle x=%.3f y=%.3f r=%.3f depth=%.3f", cx, cy, rr, d);
			}
			return fmt(
				"hole id=%%ID%% name=outlet shape=rect x=%.3f y=%.3f sx=%.3f sy=%.3f yaw=%.1f depth=%.3f", cx, cy, sx,
				sy, yaw, d);
		}
		case HazardKind::SmallBox: {
			const double sx = r.u(0.08, 0.25), sy = r.u(0.08, 0.25), sz = r.u(0.05, 0.15), yaw = r.u(-45, 45);
			aabb(sx, sy, yaw);
			return fmt(
				"box id=%%ID%% name=small_box x=%.3f y=%.3f sx=%.3f sy=%.3f sz=%.3f yaw=%.1f", cx, cy, sx, sy, sz, yaw);
		}
		case HazardKind::Table: {
			const double sx = r.u(0.6, 1.0), sy = r.u(0.6, 1.0), h = r.u(0.45, 0.75), yaw = r.u(-20, 20);
			aabb(sx, sy, yaw);
			return fmt(
				"table id=%%ID%% name=table x=%.3f y=%.3f yaw=%.1f sx=%.3f sy=%.3f height=%.3f top=0.04 leg=0.05", cx,
				cy, yaw, sx, sy, h);
		}
		case HazardKind::CableProtector: {
			// free-standing: a short one (a cable across part of the floor)
			const double sx = r.u(0.2, 0.3), sy = r.u(0.6, 1.2), sz = r.u(0.03, 0.05), yaw = r.u(-30, 30);
			aabb(sx, sy, yaw);
			return fmt(
				"box id=%%ID%% name=cable_protector x=%.3f y=%.3f sx=%.3f sy=%.3f sz=%.3f yaw=%.1f", cx, cy, sx, sy, sz,
				yaw);
		}
		case HazardKind::Ramp: {
			// up, plateau, down: centred on (cx, cy) along yaw
			const double len = r.u(0.5, 0.8), w = r.u(0.7, 1.0), ang = r.u(3, 6), plat = r.u(0.2, 0.4);
			const double yaw = r.coin() ? r.u(-20, 20) : 90 + r.u(-20, 20);
			const double along = len + plat / 2;
			aabb(2 * along, w, yaw);
			const double x = cx - along * std::cos(yaw * kDeg), y = cy - along * std::sin(yaw * kDeg);
			return fmt(
				"ramp id=%%ID%% name=ramp x=%.3f y=%.3f yaw=%.1f length=%.3f width=%.3f angle=%.2f plateau=%.3f back=1",
				x, y, yaw, len, w, ang, plat);
		}
		default: break;
	}
	throw std::logic_error("freeHazard: not a free-standing kind");
}

/** One layout from the stream (may fail the checks). */
Layout drawLayout(Rand& r, unsigned seed, Corridor& c)
{
	Layout lay;
	c.W = r.u(2.8, 3.6);
	c.L = r.u(5.5, 7.0);
	c.x0 = -1.0;
	c.x1 = c.L + 1.0;
	c.room = r.coin();
	if (c.room)
	{
		c.a = r.u(1.2, 2.2);
		c.b = std::min(c.a + r.u(2.5, 3.5), c.L - 0.6);
		const int sides = r.i(3);  // 0 top, 1 bottom, 2 both
		c.eTop = sides != 1 ? r.u(0.8, 1.5) : 0;
		c.eBot = sides != 0 ? r.u(0.8, 1.5) : 0;
	}
	const double h = c.W / 2;
	// the walls (ids first, so that the hazards' ids follow)
	addWall(lay, "back_wall", c.x0, -h - (c.room ? 0 : 0), c.x0, h);
	addWall(lay, "end_wall", c.x1, -h, c.x1, h);
	for (int side = 0; side < 2; side++)
	{
		const double s = side == 0 ? 1 : -1, e = side == 0 ? c.eTop : c.eBot;
		const char* nm = side == 0 ? "left_wall" : "right_wall";
		if (c.room && e > 0)
		{
			addWall(lay, nm, c.x0, s * h, c.a, s * h);
			addWall(lay, nm, c.a, s * h, c.a, s * (h + e));
			addWall(lay, nm, c.a, s * (h + e), c.b, s * (h + e));
			addWall(lay, nm, c.b, s * (h + e), c.b, s * h);
			addWall(lay, nm, c.b, s * h, c.x1, s * h);
		}
		else
			addWall(lay, nm, c.x0, s * h, c.x1, s * h);
	}

	lay.start = Eigen::Vector2d(0, snap(r.u(-0.4, 0.4), 0.01));
	lay.goal = Eigen::Vector2d(snap(c.L, 0.01), snap(r.u(-0.4, 0.4), 0.01));
	lay.taken.push_back(boxAround(lay.start.x(), lay.start.y(), 0.9, 0.9));
	lay.taken.push_back(boxAround(lay.goal.x(), lay.goal.y(), 0.9, 0.9));

	// The hazard on the straight line: the kinds cycle with the seed.
	const HazardKind lineKinds[] = {HazardKind::Hole,      HazardKind::Outlet,         HazardKind::StepDown,
									HazardKind::Stairwell, HazardKind::CableProtector, HazardKind::SmallBox,
									HazardKind::Table};
	const HazardKind k = lineKinds[seed % 7];
	const double s = r.u(0.40, 0.60);
	const Eigen::Vector2d P = lay.start + s * (lay.goal - lay.start);
	lay.lineKind = k;
	// the wall-attached kinds reach from the wall on the line's side to 0.25-0.4 m
	// beyond the line: the way around is on the other side, >= 1.0 m wide
	// (W/2 >= 1.4, the edge at most 0.4 m past the line, |line y| <= 0.4 here)
	const double side = P.y() >= 0 ? 1 : -1;
	const double wallY = side * h;  // P.x is before the room or in it; the room widens it further
	const double wallAtP = side > 0 ? c.yTop(P.x()) : c.yBot(P.x());
	const double edge = P.y() - side * r.u(0.25, 0.4);
	Eigen::Vector2d half(0, 0);
	switch (k)
	{
		case HazardKind::StepDown: {
			const double sx = r.u(0.8, 1.4), sy = std::abs(wallAtP - edge) + 0.05, d = r.u(0.10, 0.20);
			lay.lineId = addHazard(
				lay, k, true,
				fmt("hole id=%%ID%% name=step_down shape=rect x=%.3f y=%.3f sx=%.3f sy=%.3f depth=%.3f", P.x(),
					(wallAtP + edge) / 2, sx, sy, d));
			lay.taken.push_back(boxAround(P.x(), (wallAtP + edge) / 2, sx / 2 + 0.55, sy / 2 + 0.55));
			break;
		}
		case HazardKind::Stairwell: {
			// descends from its top edge (at `edge`) towards the wall; the landing fills the rest
			const int steps = 2 + r.i(3);
			const double run = 0.28, rise = r.u(0.15, 0.18), w = r.u(0.9, 1.2);
			const double len = std::abs(wallAtP - edge) + 0.05, landing = std::max(0.2, len - steps * run);
			lay.lineId = addHazard(
				lay, k, true,
				fmt("stairs_down id=%%ID%% name=stairwell x=%.3f y=%.3f yaw=%.1f width=%.3f steps=%d rise=%.3f "
					"run=%.3f landing=%.3f",
					P.x(), edge, side * 90.0, w, steps, rise, run, landing));
			lay.taken.push_back(boxAround(P.x(), (wallAtP + edge) / 2, w / 2 + 0.55, len / 2 + 0.55));
			break;
		}
		case HazardKind::CableProtector: {
			const double sx = r.u(0.2, 0.3), sy = std::abs(wallAtP - edge), sz = r.u(0.03, 0.05), yaw = r.u(-8, 8);
			lay.lineId = addHazard(
				lay, k, true,
				fmt("box id=%%ID%% name=cable_protector x=%.3f y=%.3f sx=%.3f sy=%.3f sz=%.3f yaw=%.1f", P.x(),
					(wallAtP + edge) / 2, sx, sy, sz, yaw));
			lay.taken.push_back(boxAround(P.x(), (wallAtP + edge) / 2, sx / 2 + 0.55, sy / 2 + 0.55));
			break;
		}
		default: {
			// free-standing, centred within a few cm of the line (the outlet exactly on it)
			const double off = k == HazardKind::Outlet ? 0.0 : r.u(-0.1, 0.1);
			const std::string st = freeHazard(r, k, P.x(), P.y() + off, half);
			lay.lineId = addHazard(lay, k, true, st);
			lay.taken.push_back(boxAround(P.x(), P.y() + off, half.x() + 0.55, half.y() + 0.55));
			// Passages beside it: closed (< 0.15 m) or at least 1.1 m wide. A
			// narrower one lets the planner's radius (0.30 m) through on the ground
			// truth and closes as the noisy map's edges grow: a trap that tests
			// squeezing through, not seeing the hazard. Such a layout is drawn again.
			const double top = std::min(c.yTop(P.x() - half.x()), c.yTop(P.x() + half.x()));
			const double bot = std::max(c.yBot(P.x() - half.x()), c.yBot(P.x() + half.x()));
			for (const double gap : {top - (P.y() + off + half.y()), (P.y() + off - half.y()) - bot})
				if (gap > 0.15 && gap < 1.1) lay.ok = false;
			break;
		}
	}
	(void)wallY;

	// 1-3 further hazards and, on half of the seeds, a ramp, anywhere clear.
	const HazardKind others[] = {HazardKind::Hole,     HazardKind::Outlet, HazardKind::CableProtector,
								 HazardKind::SmallBox, HazardKind::Table,  HazardKind::Outlet};
	std::vector<HazardKind> extra;
	for (int n = 1 + r.i(3); n > 0; n--) extra.push_back(others[r.i(6)]);
	if (r.coin()) extra.push_back(HazardKind::Ramp);
	for (const HazardKind e : extra)
		for (int tries = 0; tries < 60; tries++)
		{
			// against a wall (half of them) or at least 1.1 m from both walls, and
			// 1.1 m from the other hazards: no passage narrower than 1.1 m
			const double x = r.u(0.8, c.L - 0.3);
			const bool againstWall = r.coin(), top = r.coin();
			double y = r.u(c.yBot(x) + 0.4, c.yTop(x) - 0.4);
			Rand probe = r;  // the size first, the same draw if the place is kept
			Eigen::Vector2d hs;
			std::string st = freeHazard(probe, e, x, y, hs);
			const double yTop = std::min(c.yTop(x - hs.x()), c.yTop(x + hs.x()));
			const double yBot = std::max(c.yBot(x - hs.x()), c.yBot(x + hs.x()));
			if (againstWall)
			{
				y = top ? yTop - 0.05 - hs.y() : yBot + 0.05 + hs.y();
				probe = r;
				st = freeHazard(probe, e, x, y, hs);
			}
			// (a ramp is traversable along its axis: 0.3 m around it is enough)
			const double margin = e == HazardKind::Ramp ? 0.3 : 0.55;
			const Eigen::AlignedBox2d b = boxAround(x, y, hs.x() + margin, hs.y() + margin);
			const bool inside = againstWall ? y - hs.y() > yBot && y + hs.y() < yTop
											: y - hs.y() > yBot + 1.1 && y + hs.y() < yTop - 1.1;
			if (!lay.clear(b) || !inside) continue;
			r = probe;
			addHazard(lay, e, false, st);
			lay.taken.push_back(b);
			break;
		}

	// 0-2 people crossing the corridor AHEAD of the walker (present only while
	// crossing, then gone through a door in the wall). The walker drives at most
	// 0.5 m/s (the nav example's maxSpeed), so by time t its centre is at most
	// 0.5 t along x from the start (x = 0). A crossing at x_p ends by the time the
	// walker could be 1.4 m short of x_p (its footprint reaches 0.36 m ahead, the
	// person 0.2 m back: 0.84 m to spare) and starts at most 4 s earlier than the
	// walker could be 3 m short of it: the camera sees the person cross and leave
	// its trail on the floor, the test is the map's (issue #14), and a person
	// never walks into the walker's side, which no map could avoid.
	for (int n = r.i(3); n > 0; n--)
	{
		const double x = r.u(3.0, c.L - 0.3);
		const bool down = r.coin();
		const double yA = c.yTop(x) - 0.3, yB = c.yBot(x) + 0.3;
		const double y0 = down ? yA : yB, y1 = down ? yB : yA;
		const double speed = r.u(0.8, 1.3);
		const double D = std::abs(y1 - y0) / speed;  // crossing time [s]
		const double latestEnd = (x - 1.4) / 0.5, earliestEnd = std::max(D + 0.5, (x - 3.0) / 0.5 - 4.0 + D);
		if (latestEnd < earliestEnd) continue;
		const double tEnd = r.u(earliestEnd, latestEnd);
		const int f1 = int(std::floor(tEnd * 10)), f0 = std::max(1, f1 - int(std::ceil(D * 10)));
		addHazard(
			lay, HazardKind::Person, false,
			fmt("box id=%%ID%% name=person x=%.3f y=%.3f sx=0.40 sy=0.30 sz=1.70 frames=%d-%d to=%.3f,%.3f "
				"category=large",
				x, y0, f0, f1, x, y1));
	}
	return lay;
}
}  // namespace

Scene staticPart(const Scene& scene)
{
	Scene s = scene;
	auto moving = [&](int id) {
		const ObjectInfo* o = scene.object(id);
		return o && o->dynamic();
	};
	s.solids.erase(
		std::remove_if(s.solids.begin(), s.solids.end(), [&](const ConvexSolid& c) { return moving(c.object_id); }),
		s.solids.end());
	s.holes.erase(
		std::remove_if(s.holes.begin(), s.holes.end(), [&](const Hole& h) { return moving(h.object_id); }),
		s.holes.end());
	return s;
}

GroundTruthGrid staticGroundTruth(const SceneFile& sf)
{
	Scene s = staticPart(sf.scene);
	GroundTruthGrid gt;
	gt.build(s, sf.grid);
	return gt;
}

std::vector<uint8_t> blockedCells(const GroundTruthGrid& gt, double radius)
{
	const int nx = gt.spec.nx(), ny = gt.spec.ny();
	std::vector<uint8_t> out(size_t(nx) * size_t(ny), 0);
	const double rc = radius / gt.spec.resolution;  // in cells, centre to centre
	const int R = int(std::floor(rc));
	std::vector<Eigen::Vector2i> disk;
	for (int dy = -R; dy <= R; dy++)
		for (int dx = -R; dx <= R; dx++)
			if (dx * dx + dy * dy <= rc * rc + 1e-9) disk.emplace_back(dx, dy);
	for (int iy = 0; iy < ny; iy++)
		for (int ix = 0; ix < nx; ix++)
		{
			const Label l = gt.geomLabel[gt.idx(ix, iy)];
			if (l != Label::Obstacle && l != Label::Drop) continue;
			for (const auto& d : disk)
			{
				const int x = ix + d.x(), y = iy + d.y();
				if (x >= 0 && y >= 0 && x < nx && y < ny) out[gt.idx(x, y)] = 1;
			}
		}
	return out;
}

namespace
{
/** Dijkstra over the free cells from `src` (8-connected). */
std::vector<float> dijkstra(const GroundTruthGrid& gt, const std::vector<uint8_t>& blocked, int sx, int sy)
{
	const int nx = gt.spec.nx(), ny = gt.spec.ny();
	const float inf = std::numeric_limits<float>::infinity();
	std::vector<float> dist(size_t(nx) * size_t(ny), inf);
	if (sx < 0 || sy < 0 || sx >= nx || sy >= ny || blocked[gt.idx(sx, sy)]) return dist;
	using Item = std::pair<float, int>;
	std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
	dist[gt.idx(sx, sy)] = 0;
	q.push({0.f, int(gt.idx(sx, sy))});
	const float res = float(gt.spec.resolution), diag = float(gt.spec.resolution * std::sqrt(2.0));
	while (!q.empty())
	{
		const auto [d, i] = q.top();
		q.pop();
		if (d > dist[size_t(i)]) continue;
		const int x = i % nx, y = i / nx;
		for (int dy = -1; dy <= 1; dy++)
			for (int dx = -1; dx <= 1; dx++)
			{
				if (!dx && !dy) continue;
				const int X = x + dx, Y = y + dy;
				if (X < 0 || Y < 0 || X >= nx || Y >= ny) continue;
				const size_t j = gt.idx(X, Y);
				if (blocked[j]) continue;
				const float nd = d + (dx && dy ? diag : res);
				if (nd < dist[j])
				{
					dist[j] = nd;
					q.push({nd, int(j)});
				}
			}
	}
	return dist;
}
}  // namespace

GridPath shortestFreePath(const GroundTruthGrid& gt, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double radius)
{
	GridPath p;
	int ax, ay, bx, by;
	if (!gt.cellOf(a.x(), a.y(), ax, ay) || !gt.cellOf(b.x(), b.y(), bx, by)) return p;
	const auto blocked = blockedCells(gt, radius);
	const auto d = dijkstra(gt, blocked, ax, ay);
	const float v = d[gt.idx(bx, by)];
	p.found = std::isfinite(v);
	p.length = p.found ? v : 0;
	return p;
}

std::vector<float> distanceField(const GroundTruthGrid& gt, const Eigen::Vector2d& goal, double radius)
{
	int gx, gy;
	const auto blocked = blockedCells(gt, radius);
	if (!gt.cellOf(goal.x(), goal.y(), gx, gy))
		return std::vector<float>(blocked.size(), std::numeric_limits<float>::infinity());
	return dijkstra(gt, blocked, gx, gy);
}

int firstHazardOnSegment(
	const GroundTruthGrid& gt, const Eigen::Vector2d& a, const Eigen::Vector2d& b, const std::vector<int>& ignore,
	double* at)
{
	const double len = (b - a).norm(), step = gt.spec.resolution / 4;
	for (double s = 0; s <= len; s += step)
	{
		const Eigen::Vector2d p = a + (len > 0 ? s / len : 0) * (b - a);
		int ix, iy;
		if (!gt.cellOf(p.x(), p.y(), ix, iy)) continue;
		const size_t i = gt.idx(ix, iy);
		const Label l = gt.geomLabel[i];
		if (l != Label::Obstacle && l != Label::Drop) continue;
		if (std::find(ignore.begin(), ignore.end(), gt.objectId[i]) != ignore.end()) continue;
		if (at) *at = s;
		return gt.objectId[i];
	}
	return 0;
}

GeneratedScene generateScene(unsigned seed, const GeneratorOptions& opts)
{
	Rand r(seed * 2654435761u + 12345u);
	for (int attempt = 1; attempt <= opts.maxAttempts; attempt++)
	{
		Corridor c;
		Layout lay = drawLayout(r, seed, c);
		if (!lay.ok) continue;
		const double yMin = -c.W / 2 - c.eBot, yMax = c.W / 2 + c.eTop;
		const double res = opts.resolution;
		const bool people = std::any_of(lay.hazards.begin(), lay.hazards.end(), [](const GeneratedHazard& h) {
			return h.kind == HazardKind::Person;
		});

		std::ostringstream t;
		t << "# generated by gam::sim::generateScene(seed=" << seed << "), layout " << attempt << " of its stream\n";
		t << fmt(
			"# start=%.2f,%.2f goal=%.2f,%.2f (the navigation benchmark's, gam-navbench)\n", lay.start.x(),
			lay.start.y(), lay.goal.x(), lay.goal.y());
		t << "# corridor " << fmt("%.2f m wide", c.W)
		  << (c.room ? fmt(", a room x %.2f-%.2f (+%.2f m left, +%.2f m right)", c.a, c.b, c.eTop, c.eBot) : "")
		  << "; on the straight line: " << hazardKindName(lay.lineKind) << " (id " << lay.lineId << ")\n";
		t << "kinect pose=0.10,0,1.00,0,25,0      # Kinect One 1.0 m high, pitched 25 deg down\n";
		t << "leddar pose=0.20,0,0.30,0,0,0       # Leddar IS16 0.3 m high, level\n";
		const double yaw = std::atan2(lay.goal.y() - lay.start.y(), lay.goal.x() - lay.start.x());
		t << fmt("path waypoints=%.3f,%.3f,%.2f rate=10\n", lay.start.x(), lay.start.y(), yaw / kDeg);
		t << "odometry_noise xy=0 yaw=0 turn=0\n";
		for (const auto& l : lay.lines) t << l << "\n";
		t << fmt(
			"grid resolution=%.2f min_x=%.2f max_x=%.2f min_y=%.2f max_y=%.2f%s\n", res, snap(c.x0 - 0.5, res),
			snap(c.x1 + 0.5, res), snap(yMin - 0.5, res), snap(yMax + 0.5, res), people ? " per_frame=1" : "");

		GeneratedScene g;
		g.seed = seed;
		g.attempts = attempt;
		g.text = t.str();
		std::istringstream in(g.text);
		g.file = parseScene(in, "generated seed " + std::to_string(seed));
		g.start = lay.start;
		g.goal = lay.goal;
		g.startYaw = yaw;
		g.hazards = lay.hazards;
		g.lineHazard = lay.lineKind;
		g.lineHazardId = lay.lineId;

		// the checks, on the static ground truth (the people move and leave)
		const GroundTruthGrid gt = staticGroundTruth(g.file);
		double at = 0;
		if (!firstHazardOnSegment(gt, g.start, g.goal, lay.walls, &at)) continue;
		const GridPath p = shortestFreePath(gt, g.start, g.goal, opts.walkerRadius);
		if (!p.found) continue;
		g.lineHazardAt = at;
		g.gtPathLength = p.length;
		return g;
	}
	throw std::runtime_error(
		"generateScene: no layout with a hazard on the line and a free path around it in " +
		std::to_string(opts.maxAttempts) + " attempts for seed " + std::to_string(seed));
}

std::string withApproachPath(const GeneratedScene& g, double metres, double spacing)
{
	if (!(metres > 0) || !(spacing > 0) || !std::isfinite(metres) || !std::isfinite(spacing))
		throw std::invalid_argument("approach path: metres and spacing must be > 0");
	const std::string key = "\npath waypoints=";
	const size_t at = g.text.find(key);
	const size_t end = at == std::string::npos ? at : g.text.find('\n', at + 1);
	if (end == std::string::npos) throw std::invalid_argument("approach path: the scene has no path line");
	// The file holds the ends to 1 mm; the frames split the segment between
	// the rounded ends into n equal steps. samplePath takes ceil(length /
	// spacing) steps, so the spacing written is that step rounded up (to
	// 1e-6 m): n steps, never n + 1 for a segment a rounding longer.
	const auto mm = [](double v) { return std::round(v * 1000.0) / 1000.0; };
	const Eigen::Vector2d dir = (g.goal - g.start).normalized();
	const Eigen::Vector2d from(mm(g.start.x()), mm(g.start.y()));
	const Eigen::Vector2d to(mm(g.start.x() + metres * dir.x()), mm(g.start.y() + metres * dir.y()));
	const int n = std::max(1, int(std::lround(metres / spacing)));
	const double step = std::ceil((to - from).norm() / n * 1e6) / 1e6;
	const double yawDeg = g.startYaw / kDeg;
	const std::string line =
		fmt("path waypoints=%.3f,%.3f,%.2f;%.3f,%.3f,%.2f spacing=%.6f", from.x(), from.y(), yawDeg, to.x(), to.y(),
			yawDeg, step);
	return g.text.substr(0, at + 1) + line + g.text.substr(end);
}

void writeGeneratedScene(const GeneratedScene& g, const std::string& file, double approachMetres)
{
	std::ofstream f(file);
	f << (approachMetres > 0 ? withApproachPath(g, approachMetres) : g.text);
	if (!f) throw std::runtime_error("cannot write " + file);
}

FrameGroundTruth::FrameGroundTruth(const Scene& scene, const GridSpec& spec) : m_scene(scene)
{
	Scene s0 = m_scene.atFrame(0);
	m_gt.build(s0, spec);
	m_frame = 0;
}

void FrameGroundTruth::setFrame(int f)
{
	if (f == m_frame || !m_scene.dynamic()) return;
	std::vector<Eigen::AlignedBox2d> changed;
	for (const auto& o : m_scene.objects)
	{
		if (!o.dynamic()) continue;
		const bool was = o.presentAt(m_frame), is = o.presentAt(f);
		if (was == is && (!is || o.offsetAt(m_frame) == o.offsetAt(f))) continue;
		Eigen::AlignedBox2d b = m_scene.footprintAt(o.id, m_frame);
		b.extend(m_scene.footprintAt(o.id, f));
		changed.push_back(b);
	}
	m_frame = f;
	if (changed.empty()) return;
	const Scene sf = m_scene.atFrame(f);
	for (const auto& b : changed) m_gt.relabel(sf, b);
}

}  // namespace gam::sim
