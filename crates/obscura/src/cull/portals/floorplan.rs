//! 2D floor plans extruded to cells, portals and walls (seed 000 "από-Περιοχή (1)": "the
//! simple form: the scene is a 2D floor plan, cells and portals parallel to the x and y
//! axes").
//!
//! A [`FloorPlan`] holds convex rooms drawn in the ground plane (x, z), doors as
//! segments on the walls two rooms share, a wall height and furniture. [`FloorPlan::build`]
//! gives BOTH the [`CellGraph`] (a cell per room: the room's polygon extruded from the
//! floor at y = 0 to the ceiling at y = height; a portal per door: the door's rectangle
//! from the floor to its lintel) AND the scene: walls with holes exactly where the
//! portals are, a floor and (optionally) a ceiling per room, and the furniture. Every
//! object goes in each cell its bounds meet ([`assign_objects`]), so a wall between two
//! rooms is in both.
//!
//! Walls have no thickness: a wall two rooms share is one open (two-sided) surface, made
//! once, so no two faces are coplanar. Walls are cut into quads at every door edge and at
//! every door height of the plan, so wall pieces meet edge to edge (no T-junction on a
//! wall, where rasterization could leave pinholes that see into other cells).

use std::sync::Arc;

use glam::{DMat4, DVec2, DVec3};

use super::model::{Cell, CellGraph, Portal};
use crate::geom::{Aabb, Plane};
use crate::rng::SplitMix64;
use crate::scene::{Camera, Mesh, MeshBuilder, ObjectDesc, Scene};
use crate::{Error, Result};

/// A convex room of a floor plan: a polygon in the ground plane, `(x, z)` per vertex
/// (either orientation).
#[derive(Clone, Debug, PartialEq)]
pub struct Room {
    /// The cell's name.
    pub name: String,
    /// The vertices `(x, z)`, convex, in order.
    pub polygon: Vec<DVec2>,
}

impl Room {
    /// An axis-aligned rectangular room `[x0, x1] x [z0, z1]`.
    #[must_use]
    pub fn rect(name: impl Into<String>, x0: f64, z0: f64, x1: f64, z1: f64) -> Room {
        Room {
            name: name.into(),
            polygon: vec![
                DVec2::new(x0, z0),
                DVec2::new(x1, z0),
                DVec2::new(x1, z1),
                DVec2::new(x0, z1),
            ],
        }
    }

    /// The polygon counter-clockwise in `(x, z)` (positive shoelace area).
    fn ccw(&self) -> Vec<DVec2> {
        let mut p = self.polygon.clone();
        if signed_area(&p) < 0.0 {
            p.reverse();
        }
        p
    }
}

fn signed_area(p: &[DVec2]) -> f64 {
    (0..p.len())
        .map(|i| p[i].perp_dot(p[(i + 1) % p.len()]))
        .sum::<f64>()
        * 0.5
}

/// A door: an opening from the floor to `height` along the segment `a..b` of the wall
/// two rooms share; it becomes a portal.
#[derive(Clone, Debug, PartialEq)]
pub struct Door {
    /// The two rooms (indices into [`FloorPlan::rooms`]).
    pub rooms: [usize; 2],
    /// One end of the opening, `(x, z)`.
    pub a: DVec2,
    /// The other end.
    pub b: DVec2,
    /// Height of the opening (its lintel), at most the wall height.
    pub height: f64,
}

/// A piece of furniture: a closed convex object standing in a room.
#[derive(Clone, Debug, PartialEq)]
pub enum Furniture {
    /// An axis-aligned box.
    Box {
        /// Its name.
        name: String,
        /// Lower corner.
        min: DVec3,
        /// Upper corner.
        max: DVec3,
        /// Colour.
        color: [f32; 3],
    },
    /// A sphere (a UV sphere of 16 x 8).
    Sphere {
        /// Its name.
        name: String,
        /// Centre.
        center: DVec3,
        /// Radius.
        radius: f64,
        /// Colour.
        color: [f32; 3],
    },
}

/// A floor plan: rooms, doors, wall height, furniture.
#[derive(Clone, Debug, PartialEq)]
pub struct FloorPlan {
    /// The rooms (cells), convex.
    pub rooms: Vec<Room>,
    /// The doors (portals).
    pub doors: Vec<Door>,
    /// Wall height: cells run from y = 0 to y = height.
    pub height: f64,
    /// Whether rooms get a ceiling (a floor they always get).
    pub ceiling: bool,
    /// Furniture.
    pub furniture: Vec<Furniture>,
}

const WALL_COLOR: [f32; 3] = [0.82, 0.8, 0.74];
const FLOOR_COLOR: [f32; 3] = [0.55, 0.45, 0.35];
const CEILING_COLOR: [f32; 3] = [0.92, 0.92, 0.9];

impl FloorPlan {
    /// A plan of these rooms and doors, `height` high, with a ceiling and no furniture.
    #[must_use]
    pub fn new(rooms: Vec<Room>, doors: Vec<Door>, height: f64) -> FloorPlan {
        FloorPlan {
            rooms,
            doors,
            height,
            ceiling: true,
            furniture: Vec::new(),
        }
    }

    fn check(&self) -> Result<()> {
        let bad = |what: String, message: &str| Error::InvalidObject {
            object: what,
            message: message.to_string(),
        };
        if !(self.height.is_finite() && self.height > 0.0) {
            return Err(Error::option("height", "the wall height must be positive"));
        }
        for r in &self.rooms {
            if let Err(m) = convex_ccw(&r.polygon) {
                return Err(bad(format!("room \"{}\"", r.name), m));
            }
        }
        for (i, d) in self.doors.iter().enumerate() {
            let what = format!("door {i}");
            if d.rooms.iter().any(|&r| r >= self.rooms.len()) || d.rooms[0] == d.rooms[1] {
                return Err(bad(what, "must join two different rooms of the plan"));
            }
            if !(d.a.is_finite() && d.b.is_finite() && d.a.distance(d.b) > 1e-9) {
                return Err(bad(what, "has no width"));
            }
            if !(d.height.is_finite() && d.height > 0.0 && d.height <= self.height) {
                return Err(bad(what, "height must be in (0, wall height]"));
            }
        }
        Ok(())
    }

    /// The cells and portals, and the scene (walls with door holes, floors, ceilings,
    /// furniture) with its objects assigned to the cells. Errors name the room or door
    /// that is wrong (not convex, no area, a door joining unknown rooms).
    pub fn build(&self) -> Result<(CellGraph, Scene)> {
        self.check()?;
        let h = self.height;
        let rooms: Vec<Vec<DVec2>> = self.rooms.iter().map(Room::ccw).collect();
        let at = |p: DVec2, y: f64| DVec3::new(p.x, y, p.y);
        // Cells.
        let mut cells = Vec::new();
        for (room, poly) in self.rooms.iter().zip(&rooms) {
            cells.push(Cell {
                name: room.name.clone(),
                planes: prism_planes(poly, 0.0, h),
                objects: Vec::new(),
            });
        }
        // Portals.
        let portals: Vec<Portal> = self
            .doors
            .iter()
            .map(|d| Portal {
                cells: [d.rooms[0] as u32, d.rooms[1] as u32],
                polygon: vec![
                    at(d.a, 0.0),
                    at(d.b, 0.0),
                    at(d.b, d.height),
                    at(d.a, d.height),
                ],
            })
            .collect();
        // Heights at which every wall is cut.
        let mut levels = vec![0.0, h];
        for d in &self.doors {
            if d.height < h && !levels.iter().any(|&l: &f64| (l - d.height).abs() < 1e-12) {
                levels.push(d.height);
            }
        }
        levels.sort_by(f64::total_cmp);
        let mut scene = Scene::new();
        for (ri, poly) in rooms.iter().enumerate() {
            let n = poly.len();
            for ei in 0..n {
                let (a, b) = (poly[ei], poly[(ei + 1) % n]);
                let len = a.distance(b);
                let dir = (b - a) / len;
                let on_line = |p: DVec2| (p - a).perp_dot(dir).abs() <= 1e-9 * (1.0 + len);
                let t_of = |p: DVec2| (p - a).dot(dir);
                // Parts shared with an earlier room were built by it.
                let mut shared: Vec<(f64, f64)> = Vec::new();
                for (rj, other) in rooms.iter().enumerate().take(ri) {
                    let _ = rj;
                    for fj in 0..other.len() {
                        let (c, d) = (other[fj], other[(fj + 1) % other.len()]);
                        if on_line(c) && on_line(d) && (d - c).dot(dir) < 0.0 {
                            let (t0, t1) = (t_of(d).max(0.0), t_of(c).min(len));
                            if t1 > t0 {
                                shared.push((t0, t1));
                            }
                        }
                    }
                }
                let mut doors: Vec<(f64, f64, f64)> = Vec::new();
                for d in &self.doors {
                    if d.rooms.contains(&ri) && on_line(d.a) && on_line(d.b) {
                        let (t0, t1) = (t_of(d.a), t_of(d.b));
                        doors.push((t0.min(t1).max(0.0), t0.max(t1).min(len), d.height));
                    }
                }
                // Also doors of other rooms on this line (an earlier room's door on a
                // wall this room builds): all doors on the line cut the wall.
                for d in &self.doors {
                    if !d.rooms.contains(&ri) && on_line(d.a) && on_line(d.b) {
                        let (t0, t1) = (t_of(d.a), t_of(d.b));
                        let (t0, t1) = (t0.min(t1).max(0.0), t0.max(t1).min(len));
                        if t1 > t0 {
                            doors.push((t0, t1, d.height));
                        }
                    }
                }
                let mut cuts = vec![0.0, len];
                for &(s0, s1) in &shared {
                    cuts.extend([s0, s1]);
                }
                for &(d0, d1, _) in &doors {
                    cuts.extend([d0, d1]);
                }
                cuts.retain(|t| (0.0..=len).contains(t));
                cuts.sort_by(f64::total_cmp);
                cuts.dedup_by(|x, y| (*x - *y).abs() < 1e-12);
                let mut mb = MeshBuilder::new();
                for w in cuts.windows(2) {
                    let (t0, t1) = (w[0], w[1]);
                    if t1 - t0 < 1e-12 {
                        continue;
                    }
                    let mid = 0.5 * (t0 + t1);
                    if shared.iter().any(|&(s0, s1)| mid > s0 && mid < s1) {
                        continue;
                    }
                    let open_to = doors
                        .iter()
                        .filter(|&&(d0, d1, _)| mid > d0 && mid < d1)
                        .map(|&(_, _, dh)| dh)
                        .fold(0.0, f64::max);
                    let (p0, p1) = (a + dir * t0, a + dir * t1);
                    for l in levels.windows(2) {
                        if l[1] <= open_to + 1e-12 {
                            continue;
                        }
                        // Facing into the room: seen from inside, counter-clockwise.
                        let q = [at(p0, l[0]), at(p1, l[0]), at(p1, l[1]), at(p0, l[1])];
                        let base = mb.vertex_count() as u32;
                        for p in q {
                            mb.push_position(p);
                        }
                        mb.push_face(&[base, base + 1, base + 2, base + 3], None)
                            .map_err(|e| wall_error(ri, ei, &e))?;
                    }
                }
                let mesh = mb.finish().0;
                if mesh.polygon_count() > 0 {
                    scene.add(
                        ObjectDesc::new(format!("wall {} {ei}", self.rooms[ri].name), mesh)
                            .with_color(WALL_COLOR)
                            .with_closed(false)
                            .with_convex(false),
                    )?;
                }
            }
            // Floor facing up (counter-clockwise seen from above = clockwise in (x, z)).
            let flat = |y: f64, up: bool| -> Mesh {
                let mut mb = MeshBuilder::new();
                let idx: Vec<u32> = poly.iter().map(|&p| mb.push_position(at(p, y))).collect();
                let idx: Vec<u32> = if up {
                    idx.into_iter().rev().collect()
                } else {
                    idx
                };
                mb.push_face(&idx, None).expect("indices in range");
                mb.finish().0
            };
            scene.add(
                ObjectDesc::new(format!("floor {}", self.rooms[ri].name), flat(0.0, true))
                    .with_color(FLOOR_COLOR)
                    .with_closed(false)
                    .with_convex(true),
            )?;
            if self.ceiling {
                scene.add(
                    ObjectDesc::new(format!("ceiling {}", self.rooms[ri].name), flat(h, false))
                        .with_color(CEILING_COLOR)
                        .with_closed(false)
                        .with_convex(true),
                )?;
            }
        }
        for f in &self.furniture {
            let desc = match f {
                Furniture::Box {
                    name,
                    min,
                    max,
                    color,
                } => ObjectDesc::new(name.clone(), crate::scene::demo::box_mesh(*min, *max))
                    .with_color(*color)
                    .with_closed(true)
                    .with_convex(true),
                Furniture::Sphere {
                    name,
                    center,
                    radius,
                    color,
                } => ObjectDesc::new(
                    name.clone(),
                    crate::scene::demo::uv_sphere_mesh(*radius, 16, 8),
                )
                .with_transform(DMat4::from_translation(*center))
                .with_color(*color)
                .with_closed(true)
                .with_convex(true),
            };
            scene.add(desc)?;
        }
        let mut graph = CellGraph::new(cells, portals);
        assign_objects(&mut graph, &scene);
        Ok((graph, scene))
    }
}

/// The planes (normals out) of a convex polygon of the ground plane, `(x, z)` per
/// vertex counter-clockwise (positive shoelace area in `(x, z)`), extruded from `y0` to
/// `y1`: one vertical plane per edge, then the floor and the ceiling.
#[must_use]
pub fn prism_planes(poly: &[DVec2], y0: f64, y1: f64) -> Vec<Plane> {
    let mut planes = Vec::new();
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let e = (b - a).normalize();
        // Outward for a counter-clockwise polygon in (x, z): (e.z, -e.x).
        let n = DVec3::new(e.y, 0.0, -e.x);
        planes.push(Plane::from_point_normal(DVec3::new(a.x, y0, a.y), n));
    }
    planes.push(Plane::from_point_normal(
        DVec3::new(0.0, y0, 0.0),
        DVec3::NEG_Y,
    ));
    planes.push(Plane::from_point_normal(DVec3::new(0.0, y1, 0.0), DVec3::Y));
    planes
}

/// Checks a ground-plane polygon for a room or cell: at least 3 finite vertices, an
/// area, convex; gives it counter-clockwise in `(x, z)`.
pub(crate) fn convex_ccw(polygon: &[DVec2]) -> std::result::Result<Vec<DVec2>, &'static str> {
    if polygon.len() < 3 || !polygon.iter().all(|p| p.is_finite()) {
        return Err("needs at least 3 finite vertices");
    }
    let mut p = polygon.to_vec();
    if signed_area(&p) < 0.0 {
        p.reverse();
    }
    if signed_area(&p) <= 1e-12 {
        return Err("has no area");
    }
    let n = p.len();
    for i in 0..n {
        let (a, b, c) = (p[i], p[(i + 1) % n], p[(i + 2) % n]);
        if (b - a).perp_dot(c - b) < -1e-12 {
            return Err("is not convex");
        }
    }
    Ok(p)
}

fn wall_error(room: usize, edge: usize, e: &impl std::fmt::Display) -> Error {
    Error::InvalidObject {
        object: format!("wall of room {room}, edge {edge}"),
        message: e.to_string(),
    }
}

/// Puts each object of `scene` in every cell its world bounds meet (not separated by
/// one of the cell's planes): conservative, an object spanning cells is in each; cells
/// without planes get nothing. Replaces the cells' object lists.
pub fn assign_objects(graph: &mut CellGraph, scene: &Scene) {
    for cell in &mut graph.cells {
        cell.objects.clear();
        if cell.planes.is_empty() {
            continue;
        }
        for (k, o) in scene.objects().iter().enumerate() {
            if box_meets_cell(&o.bounds, &cell.planes) {
                cell.objects.push(k as u32);
            }
        }
    }
}

/// Whether no plane of the cell has the whole box strictly in front (beyond a rounding
/// tolerance): rounds towards meeting.
pub(crate) fn box_meets_cell(b: &Aabb, planes: &[Plane]) -> bool {
    let eps = 1e-9 * (1.0 + b.min.abs().max_element().max(b.max.abs().max_element()));
    !planes
        .iter()
        .any(|pl| b.corners().iter().all(|&c| pl.signed_distance(c) > eps))
}

/// The seed's five cells A..E (ALGORITHMS.md worked example 4; seed 000
/// "από-Περιοχή (3)"), a floor plan whose visibility is exactly the seed's PVS table
///
/// ```text
///      A: {A, D, E}   B: {B, C, E}   C: {B, C, D, E}   D: {A, C, D, E}   E: all
/// ```
///
/// Cells are indexed A=0, B=1, C=2, D=3, E=4. The plan, in the ground plane (x, z),
/// walls 3 high, every door a full-height opening (so a line of sight in 3D passes the
/// doors exactly when its ground projection does: the analysis is 2D):
///
/// ```text
///   z
///   6 +-----+
///     |  A  +-----+             A = [-3,0]x[2,6]     D = [0,3]x[2,5]
///   4 |    AD  D  |             E = [0,12]x[0,2] (a long corridor)
///     |     |     |             C = [8,12]x[-4,0]    B = [8,12]x[-8,-4]
///   2 +-----+-DE--+-----------------+
///           |        E               |   AD: x=0,  z in [3.5,4.5]
///   0       +---------------+-EC-+---+   DE: z=2,  x in [1,2]
///                           |  C    |   EC: z=0,  x in [9,10]
///  -4                       +--CB---+   CB: z=-4, x in [9,10]
///                           |  B    |
///  -8                       +-------+
///   x:     0   1 2 3                8  9 10 12
/// ```
///
/// The adjacency is the chain A - D - E - C - B (portals AD, DE, EC, CB), and a cell sees
/// exactly the cells at most two portals away:
/// - **one portal** (A-D, D-E, E-C, C-B): visible, through the portal itself.
/// - **two portals** (A-E through AD, DE; D-C through DE, EC; E-B through EC, CB):
///   visible. Two portals on different walls of one convex cell: the segment joining
///   their midpoints lies in that cell and crosses both walls. E.g. (-0.75, 5) in A to
///   (2.25, 1) in E passes AD at z = 4 and DE at x = 1.5 (checked by the tests).
/// - **three portals, A-C** (AD, DE, EC): not visible. A line through AD `(0, za)`,
///   `za in [3.5, 4.5]`, and DE `(xd, 2)`, `xd in [1, 2]`, goes down to the right and
///   meets E's far wall z = 0 at `x = xd + 2 xd / (za - 2) <= 2 + 4 / 1.5 = 4.67 < 9`,
///   short of EC (x in [9, 10]).
/// - **three portals, D-B** (DE, EC, CB): not visible. A line through DE and EC runs
///   `dx/dz in [7/2, 9/2]` per unit down, so below z = 0 it leaves C through its right
///   wall x = 12 at `z = -2 (12 - xe) / (xe - xd) >= -6/7 > -4`: it never reaches CB.
/// - **four portals, A-B**: contains A-C's three, not visible.
///
/// So A: {A, D, E}; B: {B, C, E}; C: {B, C, D, E}; D: {A, C, D, E}; E: all. From E
/// looking towards D the portal walk goes E -> D (through DE) -> A (through AD) and
/// stops: A has no other portal. Each cell holds a box of furniture.
#[must_use]
pub fn seed_example() -> (CellGraph, Scene) {
    let rooms = vec![
        Room::rect("A", -3.0, 2.0, 0.0, 6.0),
        Room::rect("B", 8.0, -8.0, 12.0, -4.0),
        Room::rect("C", 8.0, -4.0, 12.0, 0.0),
        Room::rect("D", 0.0, 2.0, 3.0, 5.0),
        Room::rect("E", 0.0, 0.0, 12.0, 2.0),
    ];
    let h = 3.0;
    let door = |a: usize, b: usize, p: (f64, f64), q: (f64, f64)| Door {
        rooms: [a, b],
        a: DVec2::new(p.0, p.1),
        b: DVec2::new(q.0, q.1),
        height: h,
    };
    let doors = vec![
        door(0, 3, (0.0, 3.5), (0.0, 4.5)),    // AD
        door(3, 4, (1.0, 2.0), (2.0, 2.0)),    // DE
        door(4, 2, (9.0, 0.0), (10.0, 0.0)),   // EC
        door(2, 1, (9.0, -4.0), (10.0, -4.0)), // CB
    ];
    let mut plan = FloorPlan::new(rooms, doors, h);
    let boxes = [
        ("box A", (-2.5, 4.5), [0.9, 0.3, 0.3]),
        ("box B", (11.0, -7.0), [0.3, 0.8, 0.3]),
        ("box C", (11.0, -3.0), [0.3, 0.4, 0.9]),
        ("box D", (2.2, 4.2), [0.9, 0.8, 0.2]),
        ("box E", (6.0, 1.0), [0.7, 0.3, 0.8]),
    ];
    for (name, (x, z), color) in boxes {
        plan.furniture.push(Furniture::Box {
            name: name.into(),
            min: DVec3::new(x - 0.3, 0.0, z - 0.3),
            max: DVec3::new(x + 0.3, 0.8, z + 0.3),
            color,
        });
    }
    let (graph, mut scene) = plan.build().expect("the seed example is a valid plan");
    let graph = Arc::new(graph);
    scene.set_cells(Some(graph.clone()));
    scene.set_camera(Some(Camera::perspective(
        DVec3::new(7.0, 1.6, 1.0),
        DVec3::new(1.5, 1.5, 3.0),
        DVec3::Y,
        70.0,
        0.05,
        100.0,
    )));
    (Arc::unwrap_or_clone(graph), scene)
}

/// A generated level of `nx * nz` cells: a grid of rooms whose odd rows are corridors
/// (3 deep), every other row rooms of random sizes, doors along a random spanning tree
/// of the grid plus about a quarter of the other walls (corridor pieces always open into
/// each other), and furniture along the room walls. Deterministic for a `seed`.
#[must_use]
pub fn level_plan(nx: usize, nz: usize, seed: u64) -> FloorPlan {
    let (nx, nz) = (nx.max(1), nz.max(1));
    let mut rng = SplitMix64(seed);
    let mut xs = vec![0.0];
    for _ in 0..nx {
        let w = rng.range(4.0, 7.0);
        xs.push(xs.last().copied().unwrap_or(0.0) + w.round());
    }
    let mut zs = vec![0.0];
    for j in 0..nz {
        let d = if j % 2 == 1 {
            3.0
        } else {
            rng.range(4.0, 7.0).round()
        };
        zs.push(zs.last().copied().unwrap_or(0.0) + d);
    }
    let corridor = |j: usize| j % 2 == 1;
    let id = |i: usize, j: usize| j * nx + i;
    let mut rooms = Vec::new();
    for j in 0..nz {
        for i in 0..nx {
            let name = if corridor(j) {
                format!("corridor {i},{j}")
            } else {
                format!("room {i},{j}")
            };
            rooms.push(Room::rect(name, xs[i], zs[j], xs[i + 1], zs[j + 1]));
        }
    }
    // Walls between neighbours: (cell a, cell b, the shared segment).
    let mut walls = Vec::new();
    for j in 0..nz {
        for i in 0..nx {
            if i + 1 < nx {
                walls.push((
                    id(i, j),
                    id(i + 1, j),
                    DVec2::new(xs[i + 1], zs[j]),
                    DVec2::new(xs[i + 1], zs[j + 1]),
                ));
            }
            if j + 1 < nz {
                walls.push((
                    id(i, j),
                    id(i, j + 1),
                    DVec2::new(xs[i], zs[j + 1]),
                    DVec2::new(xs[i + 1], zs[j + 1]),
                ));
            }
        }
    }
    // A random spanning tree (Kruskal on shuffled walls), then extra doors.
    let mut order: Vec<usize> = (0..walls.len()).collect();
    for k in (1..order.len()).rev() {
        let r = (rng.next_f64() * (k + 1) as f64) as usize;
        order.swap(k, r.min(k));
    }
    let mut parent: Vec<usize> = (0..rooms.len()).collect();
    fn find(p: &mut [usize], mut x: usize) -> usize {
        while p[x] != x {
            p[x] = p[p[x]];
            x = p[x];
        }
        x
    }
    let mut open = vec![false; walls.len()];
    for &w in &order {
        let (a, b, _, _) = walls[w];
        let both_corridor = a / nx == b / nx && corridor(a / nx);
        let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
        if ra != rb {
            parent[ra] = rb;
            open[w] = true;
        } else if both_corridor || rng.next_f64() < 0.1 {
            open[w] = true;
        }
    }
    let height = 3.0;
    let mut doors = Vec::new();
    for (w, &(a, b, p, q)) in walls.iter().enumerate() {
        if !open[w] {
            continue;
        }
        let len = p.distance(q);
        let both_corridor = a / nx == b / nx && corridor(a / nx);
        let (width, dh) = if both_corridor {
            (1.0f64.min(len - 0.4), 2.6)
        } else {
            (1.2f64.min(len - 0.6), 2.2)
        };
        // Along a corridor the doors keep to one side and the other in turn (a line
        // of sight passes two of them, never three); other doors anywhere on the wall.
        let start = if both_corridor {
            if (a % nx) % 2 == 0 {
                0.2
            } else {
                len - 0.2 - width
            }
        } else {
            rng.range(0.3, (len - width - 0.3).max(0.3))
        };
        let dir = (q - p) / len;
        doors.push(Door {
            rooms: [a, b],
            a: p + dir * start,
            b: p + dir * (start + width),
            height: dh,
        });
    }
    let mut plan = FloorPlan::new(rooms, doors, height);
    // Furniture along the walls of rooms, away from doors.
    for j in (0..nz).filter(|&j| !corridor(j)) {
        for i in 0..nx {
            let (x0, x1, z0, z1) = (xs[i], xs[i + 1], zs[j], zs[j + 1]);
            let count = 1 + (rng.next_f64() * 3.0) as usize;
            for k in 0..count {
                let (sx, sz) = (rng.range(0.4, 1.0), rng.range(0.4, 1.0));
                let side = (rng.next_f64() * 4.0) as usize;
                let (cx, cz) = match side {
                    0 => (rng.range(x0 + 0.9, x1 - 0.9), z0 + 0.15 + sz),
                    1 => (rng.range(x0 + 0.9, x1 - 0.9), z1 - 0.15 - sz),
                    2 => (x0 + 0.15 + sx, rng.range(z0 + 0.9, z1 - 0.9)),
                    _ => (x1 - 0.15 - sx, rng.range(z0 + 0.9, z1 - 0.9)),
                };
                let near_door = plan.doors.iter().any(|d| {
                    let m = (d.a + d.b) * 0.5;
                    m.distance(DVec2::new(cx, cz)) < 1.8
                });
                if near_door {
                    continue;
                }
                let top = rng.range(0.5, 1.8);
                let grey = rng.range(0.35, 0.8) as f32;
                let color = [grey, grey * 0.8, grey * 0.6];
                plan.furniture.push(Furniture::Box {
                    name: format!("furniture {i},{j} {k}"),
                    min: DVec3::new(cx - sx * 0.5, 0.0, cz - sz * 0.5),
                    max: DVec3::new(cx + sx * 0.5, top, cz + sz * 0.5),
                    color,
                });
                if rng.next_f64() < 0.3 {
                    let r = 0.2f64.min(sx.min(sz) * 0.4);
                    plan.furniture.push(Furniture::Sphere {
                        name: format!("ball {i},{j} {k}"),
                        center: DVec3::new(cx, top + r, cz),
                        radius: r,
                        color: [0.85, 0.35, 0.2],
                    });
                }
            }
        }
    }
    plan
}

/// A camera walk through a plan: from the first room, along a depth-first tour of the
/// doors (through each door into a room not yet seen, and back), `legs` legs at most,
/// `per_leg` cameras per leg, eyes 1.6 above the floor looking ahead. No eye is placed
/// on a door's plane.
#[must_use]
pub fn plan_walk(plan: &FloorPlan, legs: usize, per_leg: usize) -> Vec<Camera> {
    let centre = |r: usize| {
        let p = &plan.rooms[r].polygon;
        p.iter().copied().sum::<DVec2>() / p.len() as f64
    };
    let mut waypoints: Vec<DVec2> = Vec::new();
    let mut seen = vec![false; plan.rooms.len()];
    let mut stack = vec![0usize];
    if plan.rooms.is_empty() {
        return Vec::new();
    }
    seen[0] = true;
    waypoints.push(centre(0));
    // Depth-first: (room, next door index to try).
    let mut next = vec![0usize; plan.rooms.len()];
    while let Some(&r) = stack.last() {
        if waypoints.len() > legs * 2 + 1 {
            break;
        }
        let mut moved = false;
        while next[r] < plan.doors.len() {
            let d = &plan.doors[next[r]];
            next[r] += 1;
            let other = if d.rooms[0] == r {
                d.rooms[1]
            } else if d.rooms[1] == r {
                d.rooms[0]
            } else {
                continue;
            };
            if seen[other] {
                continue;
            }
            seen[other] = true;
            waypoints.push((d.a + d.b) * 0.5);
            waypoints.push(centre(other));
            stack.push(other);
            moved = true;
            break;
        }
        if !moved {
            stack.pop();
            if let Some(&back) = stack.last() {
                waypoints.push(centre(back));
            }
        }
    }
    let eye_h = 1.6;
    let mut cams = Vec::new();
    for w in waypoints.windows(3).take(legs) {
        let (p, q, look) = (w[0], w[1], w[2]);
        for k in 0..per_leg {
            let t = (k as f64 + 0.3) / per_leg as f64;
            let e = p + (q - p) * t;
            let target = if (q - e).length() > 0.5 { q } else { look };
            if (target - e).length() < 1e-6 {
                continue;
            }
            cams.push(Camera::perspective(
                DVec3::new(e.x, eye_h, e.y),
                DVec3::new(target.x, 1.4, target.y),
                DVec3::Y,
                75.0,
                0.05,
                200.0,
            ));
        }
    }
    cams
}
