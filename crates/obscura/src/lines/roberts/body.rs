//! The body matrix of a convex polyhedron and its place in the transformed space:
//! seed 004's first stage (planes, sign correction with an interior point, the inverse
//! view transform, the bounding box, self-hidden faces with the test point at
//! infinity).

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DMat4, DVec3, DVec4};

use crate::geom::newell_normal;
use crate::scene::{EdgeAdjacency, Mesh, Object, is_convex_closed};
use crate::{Error, Result, View};

/// Two polygons lie on one plane when their unit normals differ by less than this
/// (`1 - cos`) and their offsets by less than this times the body's size.
const COPLANAR: f64 = 1e-9;
/// Cell sizes of the plane search in `body_matrix`: more than twice what a matching
/// normal (a dot product above `1 - COPLANAR`: components within 4.5e-5) and offset
/// (within `COPLANAR` of the body's size) may differ by.
const NORMAL_CELL: f64 = 1e-4;
const OFFSET_CELL: f64 = 1e-8;
/// A plane column faces away from the viewer when `E · V_j` is below minus this (the
/// columns are scaled to a largest component of 1); faces seen edge on are not hidden.
const EDGE_ON: f64 = 1e-12;

/// The body matrix of a convex polyhedron given by its polygons: one column `[a b c
/// d]` per distinct plane (polygons on one plane, such as the two triangles of a
/// square, share it), scaled to a unit normal and signed so that the interior point
/// (the average of the polygons' vertices) gives a positive product, as the seed's
/// step I.3 does. Returns the columns and the column of each polygon (`None` for a
/// polygon without a plane: fewer than three distinct points).
///
/// ```
/// use glam::{DVec3, DVec4};
/// use obscura::lines::roberts::body_matrix;
/// use obscura::scene::demo::box_mesh;
/// let cube = box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5));
/// let polygons: Vec<Vec<DVec3>> = (0..6).map(|i| cube.polygon_points(i)).collect();
/// let (columns, _) = body_matrix(&polygons);
/// // The -x face: x + 1/2 >= 0 inside (the seed's 2x + 1, halved).
/// assert_eq!(columns[0], DVec4::new(1.0, 0.0, 0.0, 0.5));
/// ```
#[must_use]
pub fn body_matrix(polygons: &[Vec<DVec3>]) -> (Vec<DVec4>, Vec<Option<usize>>) {
    let all = polygons.iter().flatten();
    let count = polygons.iter().map(Vec::len).sum::<usize>().max(1);
    let interior = all.clone().copied().sum::<DVec3>() / count as f64;
    let (lo, hi) = all.fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let size = (hi - lo).max_element().max(f64::MIN_POSITIVE);
    let mut columns: Vec<DVec4> = Vec::new();
    let mut cells: HashMap<[i64; 4], Vec<usize>> = HashMap::new();
    let mut of_polygon = Vec::with_capacity(polygons.len());
    for poly in polygons {
        let n = newell_normal(poly);
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            of_polygon.push(None);
            continue;
        }
        let n = n / len;
        let centre = poly.iter().copied().sum::<DVec3>() / poly.len() as f64;
        let d = -n.dot(centre);
        // Columns are found by cells of (normal, d / size): a matching column differs by
        // less than half a cell in each coordinate, so it lies in the polygon's cell or
        // the neighbour on the nearer side of each coordinate (16 cells), and the search
        // stays linear in the polygons (a body of a million facets has a million planes).
        let q = [
            n.x / NORMAL_CELL,
            n.y / NORMAL_CELL,
            n.z / NORMAL_CELL,
            d / size / OFFSET_CELL,
        ];
        let base = q.map(|v| v.floor() as i64);
        let mut found = None;
        'probe: for bits in 0..16u32 {
            let mut key = base;
            for (a, k) in key.iter_mut().enumerate() {
                if bits >> a & 1 == 1 {
                    *k += if q[a] - q[a].floor() < 0.5 { -1 } else { 1 };
                }
            }
            for &j in cells.get(&key).map_or(&[][..], Vec::as_slice) {
                let c: DVec4 = columns[j];
                if c.truncate().dot(n) > 1.0 - COPLANAR && (c.w - d).abs() <= COPLANAR * size {
                    found = Some(j);
                    break 'probe;
                }
            }
        }
        of_polygon.push(Some(found.unwrap_or_else(|| {
            columns.push(n.extend(d));
            cells.entry(base).or_default().push(columns.len() - 1);
            columns.len() - 1
        })));
    }
    // Step I.3: the interior point must give a positive product with every column.
    for c in &mut columns {
        if c.dot(interior.extend(1.0)) < 0.0 {
            *c = -*c;
        }
    }
    (columns, of_polygon)
}

/// Which planes of a body are self-hidden for the test point at infinity `test` (the
/// direction the viewer looks in, `w = 0`): those with `test · V_j < 0` (seed 004,
/// step I.7). Planes seen edge on (a zero product) are not hidden.
///
/// ```
/// use glam::DVec4;
/// use obscura::lines::roberts::self_hidden;
/// let v = [DVec4::new(0., 0., -2., 1.), DVec4::new(0., 0., 2., 1.)];
/// // Looking down -z: the plane 2z + 1 = 0 (the cube's back face) is hidden.
/// assert_eq!(self_hidden(&v, DVec4::new(0., 0., -1., 0.)), [false, true]);
/// ```
#[must_use]
pub fn self_hidden(columns: &[DVec4], test: DVec4) -> Vec<bool> {
    columns
        .iter()
        .map(|c| test.dot(*c) < -EDGE_ON * c.abs().max_element())
        .collect()
}

/// The view's transformed space (seed 004, step I.5): world points relative to the
/// eye, then the camera's rotation and projection, with `z` turned so that the viewer
/// sits at `+z` infinity as in the seed (larger `z` nearer). Homogeneous; nothing is
/// divided by `w` except to draw.
#[derive(Clone, Copy, Debug)]
pub(super) struct Space {
    /// World (relative to `eye`) to the transformed space, for column vectors.
    pub m: DMat4,
    /// The inverse transpose: plane columns to the transformed space.
    pub planes: DMat4,
    /// The eye (the origin of the relative world coordinates).
    pub eye: DVec3,
    /// The view's transform (its pixel mapping: z is not flipped in x, y and w).
    pub view: crate::view::ViewTransform,
}

impl Space {
    pub fn of(view: &View) -> Space {
        let t = view.transform();
        let o = t.eye_to_clip(DVec3::ZERO);
        let e = [DVec3::X, DVec3::Y, DVec3::Z].map(|a| t.eye_to_clip(a) - o);
        let to_clip = DMat4::from_cols(e[0], e[1], e[2], o);
        let flip = DMat4::from_diagonal(DVec4::new(1.0, 1.0, -1.0, 1.0));
        let m = flip * to_clip * DMat4::from_mat3(t.rotation);
        Space {
            m,
            planes: m.inverse().transpose(),
            eye: t.eye,
            view: *t,
        }
    }

    /// A world point in the transformed space.
    #[inline]
    pub fn point(&self, world: DVec3) -> DVec4 {
        self.m * (world - self.eye).extend(1.0)
    }

    /// A plane column of eye-relative world coordinates in the transformed space,
    /// scaled to a largest component of 1 (the sign is kept).
    #[inline]
    pub fn column(&self, v: DVec4) -> DVec4 {
        let c = self.planes * v;
        let big = c.abs().max_element();
        if big > 0.0 && big.is_finite() {
            c / big
        } else {
            c
        }
    }

    /// The pixel position of a transformed point (in front of the eye).
    #[inline]
    pub fn pixel(&self, x: DVec4) -> glam::DVec2 {
        self.view.clip_to_pixel(x)
    }
}

/// An edge of a body between two of its planes.
#[derive(Clone, Copy, Debug)]
pub(super) struct BodyEdge {
    /// Mesh vertex ids in scene load order.
    pub vertices: [u32; 2],
    /// The body's planes on either side.
    pub planes: [usize; 2],
    /// The scene polygons on either side (global numbers).
    pub polygons: [u32; 2],
    /// World ends.
    pub world: [DVec3; 2],
}

/// A convex body of the scene, ready for the hiding tests.
#[derive(Clone, Debug)]
pub(super) struct Body {
    /// Scene object index.
    pub object: usize,
    /// Its plane columns in the transformed space.
    pub columns: Vec<DVec4>,
    /// The columns that hide: `columns`, and the near plane when the body crosses it
    /// (the part before the near plane is not seen, as in every surface algorithm).
    pub hiding: Vec<DVec4>,
    /// Per column, whether it is self-hidden.
    pub hidden: Vec<bool>,
    /// Per column, the scene polygons (global numbers) that lie on it.
    pub plane_polygons: Vec<Vec<u32>>,
    /// Its edges between planes that differ.
    pub edges: Vec<BodyEdge>,
    /// Box of the transformed body after the divide (x, y, z; z larger nearer);
    /// infinite when it reaches the near plane.
    pub lo: DVec3,
    pub hi: DVec3,
    /// World box.
    pub world: crate::geom::Aabb,
}

/// Edge adjacency and convexity per mesh, computed once for meshes shared by several
/// objects (the city demo's buildings are one box mesh).
pub(super) type AdjacencyCache = HashMap<*const Mesh, (EdgeAdjacency, bool)>;

/// Builds the body of scene object `k`, refusing one that is not a convex closed
/// polyhedron.
pub(super) fn build(
    view: &View,
    space: &Space,
    k: usize,
    vertex_base: u32,
    cache: &mut AdjacencyCache,
) -> Result<Body> {
    let object: &Object = &view.scene().objects()[k];
    let mesh = &object.mesh;
    let (adjacency, convex) = cache.entry(Arc::as_ptr(mesh)).or_insert_with(|| {
        let a = EdgeAdjacency::new(mesh);
        let convex = is_convex_closed(mesh, &a, 1e-9);
        (a, convex)
    });
    // The object's flag may have been set by hand: the mesh is checked too.
    if !object.convex || !*convex {
        return Err(Error::InvalidObject {
            object: object.name.clone(),
            message: "Roberts' algorithm draws convex closed polyhedra only, and this \
                      object is not one (use the exact hidden-line algorithm, hlr)"
                .into(),
        });
    }
    let relative: Vec<DVec3> = mesh
        .positions()
        .iter()
        .map(|&p| object.transform.transform_point3(p) - space.eye)
        .collect();
    let polygons: Vec<Vec<DVec3>> = (0..mesh.polygon_count())
        .map(|i| {
            mesh.polygon(i)
                .iter()
                .map(|&v| relative[v as usize])
                .collect()
        })
        .collect();
    let (world_columns, of_polygon) = body_matrix(&polygons);
    let columns: Vec<DVec4> = world_columns.iter().map(|&c| space.column(c)).collect();
    let hidden = self_hidden(&columns, DVec4::new(0.0, 0.0, -1.0, 0.0));
    let base = view.polygon_base()[k];
    let mut plane_polygons = vec![Vec::new(); columns.len()];
    for (i, c) in of_polygon.iter().enumerate() {
        if let Some(c) = c {
            plane_polygons[*c].push(base + i as u32);
        }
    }
    let mut edges = Vec::new();
    for e in &adjacency.edges {
        let (Some(f), Some(g)) = (e.forward, e.backward) else {
            continue;
        };
        let (Some(pf), Some(pg)) = (of_polygon[f as usize], of_polygon[g as usize]) else {
            continue;
        };
        if pf == pg {
            continue;
        }
        edges.push(BodyEdge {
            vertices: [vertex_base + e.a, vertex_base + e.b],
            planes: [pf, pg],
            polygons: [base + f, base + g],
            world: [
                relative[e.a as usize] + space.eye,
                relative[e.b as usize] + space.eye,
            ],
        });
    }
    // Step I.6: the box of the transformed body.
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let mut crosses_near = false;
    for &r in &relative {
        let x = space.m * r.extend(1.0);
        if !(x.w > 0.0) || x.z >= x.w * (1.0 - 1e-12) {
            crosses_near = true;
            break;
        }
        let p = x.truncate() / x.w;
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let mut hiding = columns.clone();
    if crosses_near {
        lo = DVec3::splat(f64::NEG_INFINITY);
        hi = DVec3::splat(f64::INFINITY);
        hiding.push(DVec4::new(0.0, 0.0, -1.0, 1.0));
    }
    Ok(Body {
        object: k,
        columns,
        hiding,
        hidden,
        plane_polygons,
        edges,
        lo,
        hi,
        world: object.bounds,
    })
}
