//! A fluid velocity given on an unstructured CFD mesh (one-way coupling): the mesh, the
//! point locator and the interpolator of `scg-mesh`, owned together, plus the role of
//! every boundary patch. Pure functions of positions and cell hints; the systems are in
//! [`crate::stages::mesh_flow`].
//!
//! Velocities are in m/s, lengths in m.

use std::fmt;
use std::sync::Arc;

use glam::DVec3;
use scg_mesh::{
    CellField, CellTable, Hit, Interpolation, Interpolator, Location, Locator, MeshGeometry,
    PolyMesh, TableWalk,
};

use super::carrier::Place;

pub use super::patch_interaction::{
    PatchInteraction, WallFriction, coulomb_rebound, hint, rebound, rebound_velocity,
};
use super::wall_function::{FrictionVelocity, LogLaw, WallCells, slip_wall_values};
pub use landing::{Landing, MAX_REFLECTIONS, WallImpact, land};
pub use moving::{MovingFaces, Spin};

/// The near-wall velocity of a mesh flow ([`MeshFlow::with_wall_function`]).
#[derive(Clone, Debug, PartialEq)]
pub struct WallFunctionSpec {
    /// The log law.
    pub law: LogLaw,
    /// Kinematic viscosity of the fluid, m²/s.
    pub nu: f64,
    /// Where u_τ comes from.
    pub friction: FrictionVelocity,
}

/// The mesh flow as the carrier of its particles ([`MeshFlow::velocity`]).
impl super::carrier::Carrier for MeshFlow {
    #[inline(always)]
    fn at(&self, place: Place, x: DVec3) -> (DVec3, Place) {
        self.velocity_at(place, x)
    }

    /// The cell's Gauss gradient ([`MeshFlow::cell_gradient`]), as OpenFOAM's particle
    /// forces take ∇u and ∇×u from the cell field.
    fn gradient(&self, cell: u32, _x: DVec3) -> glam::DMat3 {
        self.cell_gradient(cell)
    }
}

/// What a particle meeting a boundary patch does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PatchRole {
    /// A wall: its [`PatchInteraction`] says what a particle reaching it does (rebound,
    /// stick, escape). With the contact wall model the particles meet a mesh wall of the
    /// patch's faces first (the walls stage) and the rebound is only the guard that keeps
    /// every centre inside.
    Wall,
    /// Drains: removed and counted per group as drained (escaped through the patch).
    Outlet,
    /// Particles are fed through it (`[[feeders]] patch`); one going back out through
    /// it is removed and counted as lost (escaped through the inlet).
    Inlet,
    /// Removed and counted as lost (escaped through the patch).
    Lost,
}

impl PatchRole {
    /// Name used in reports.
    pub fn name(self) -> &'static str {
        match self {
            PatchRole::Wall => "wall",
            PatchRole::Outlet => "outlet",
            PatchRole::Inlet => "inlet",
            PatchRole::Lost => "lost",
        }
    }
}

/// A flow field on a mesh, ready for queries.
///
/// It owns everything: the mesh and its geometry (shared by the [`Locator`] through `Arc`s,
/// [`Locator::owned`]), the locator (shared by the [`Interpolator`],
/// [`Interpolator::owned`]), the interpolator's point values and the [`CellTable`] of the
/// hot path; all is freed when the `MeshFlow` is dropped. Simulations built from the same
/// scene share one `MeshFlow` (`Arc`).
///
/// Queries from a particle's cell first ask the [`CellTable`] (is x still in that cell?
/// three records read); only when it is not do they walk with the locator.
pub struct MeshFlow {
    loc: Arc<Locator<'static>>,
    interp: Interpolator<'static>,
    table: Option<CellTable>,
    roles: Vec<PatchRole>,
    field_speed: (f64, f64),
    wall: Option<WallCells>,
    /// Per-cell velocity gradients, computed at the first request (the opt-in forces).
    gradients: std::sync::OnceLock<Vec<glam::DMat3>>,
    /// Boundary faces whose surface moves ([`moving`]).
    moving: Option<MovingFaces>,
}

impl fmt::Debug for MeshFlow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = self.mesh();
        f.debug_struct("MeshFlow")
            .field("cells", &m.n_cells)
            .field("faces", &m.n_faces())
            .field("points", &m.points.len())
            .field("scheme", &self.interp.scheme())
            .field("roles", &self.roles)
            .finish()
    }
}

impl MeshFlow {
    /// Prepare `field` on `mesh` with `scheme`; `roles` gives one role per patch of
    /// `mesh.patches` (a length mismatch is an error).
    pub fn new(
        mesh: PolyMesh,
        field: &CellField,
        scheme: Interpolation,
        roles: Vec<PatchRole>,
    ) -> Result<Self, scg_mesh::MeshError> {
        Self::with_wall_function(mesh, field, scheme, roles, None)
    }

    /// [`MeshFlow::new`] with, when `wall` is given, the log law of the wall in the cells
    /// next to the wall patches (see [`crate::physics::wall_function`]): the wall faces
    /// take the slip values, and a point nearer a wall than its cell's centre sees the
    /// log law's velocity.
    pub fn with_wall_function(
        mesh: PolyMesh,
        field: &CellField,
        scheme: Interpolation,
        roles: Vec<PatchRole>,
        wall: Option<&WallFunctionSpec>,
    ) -> Result<Self, scg_mesh::MeshError> {
        if roles.len() != mesh.patches.len() {
            return Err(scg_mesh::MeshError::invalid(
                "<mesh>",
                "patches",
                format!("{} roles for {} patches", roles.len(), mesh.patches.len()),
            ));
        }
        if wall.is_some() && scheme == Interpolation::Conservative {
            return Err(scg_mesh::MeshError::invalid(
                "<field>",
                "interpolation",
                "the conservative interpolation keeps the field's face fluxes; a wall \
                 function would change them (use one or the other)",
            ));
        }
        let geom = MeshGeometry::new(&mesh)?;
        scg_mesh::interp::check_field(&mesh, field)?;
        let loc = Arc::new(Locator::owned(Arc::new(mesh), Arc::new(geom))?);
        Self::on(loc, field, scheme, roles, wall, None)
    }

    /// Another field on this flow's mesh (one snapshot of an unsteady series,
    /// [`series`]): the same locator (mesh and geometry shared, not copied), roles and
    /// scheme, its own interpolator and wall function (`wall`), and a cell table of its own
    /// values on this flow's records ([`CellTable::for_field`]: the same answers as a
    /// table of its own, 0.36 kB per hexahedron against 4.5 kB). Moving faces are not
    /// carried over.
    pub fn snapshot(
        &self,
        field: &CellField,
        wall: Option<&WallFunctionSpec>,
    ) -> Result<Self, scg_mesh::MeshError> {
        scg_mesh::interp::check_field(self.mesh(), field)?;
        Self::on(
            Arc::clone(&self.loc),
            field,
            self.scheme(),
            self.roles.clone(),
            wall,
            self.table.as_ref(),
        )
    }

    /// The flow of `field` on the mesh `loc` locates in.
    fn on(
        loc: Arc<Locator<'static>>,
        field: &CellField,
        scheme: Interpolation,
        roles: Vec<PatchRole>,
        wall: Option<&WallFunctionSpec>,
        base: Option<&CellTable>,
    ) -> Result<Self, scg_mesh::MeshError> {
        let (mesh, geom) = (loc.mesh(), loc.geometry());
        let is_wall: Vec<bool> = roles.iter().map(|r| *r == PatchRole::Wall).collect();
        let (wall, slip) = match wall {
            None => (None, None),
            Some(w) => (
                Some(WallCells::new(
                    mesh,
                    geom,
                    field,
                    &is_wall,
                    w.law,
                    w.nu,
                    &w.friction,
                )),
                Some(slip_wall_values(mesh, geom, field, &is_wall)),
            ),
        };
        let field = slip.as_ref().unwrap_or(field);
        // the conservative scheme's projection takes up the balance at the outlets
        let outflow: Vec<bool> = roles.iter().map(|r| *r == PatchRole::Outlet).collect();
        let interp = Interpolator::owned_with_outflow(Arc::clone(&loc), field, scheme, &outflow)?;
        // another field on a flow's mesh: its values on that flow's records
        let table = match base {
            Some(b) => b.for_field(&interp),
            None => CellTable::new(&interp),
        };
        let (lo, hi) = field
            .cells
            .iter()
            .map(|u| u.length())
            .fold((f64::INFINITY, 0.0_f64), |(a, b), s| (a.min(s), b.max(s)));
        Ok(MeshFlow {
            loc,
            interp,
            table,
            roles,
            field_speed: (lo, hi),
            wall,
            gradients: std::sync::OnceLock::new(),
            moving: None,
        })
    }

    /// The field's cell values, m/s.
    pub fn cell_values(&self) -> &[DVec3] {
        self.interp.cell_values()
    }

    /// The wall-adjacent cells of the wall function (`None` without one).
    pub fn wall_cells(&self) -> Option<&WallCells> {
        self.wall.as_ref()
    }

    /// `u`, the interpolated velocity at x in cell `c`, with the wall function's log law
    /// where x is nearer a wall than the centre of its wall-adjacent cell (unchanged
    /// without a wall function), m/s.
    #[inline(always)]
    pub fn near_wall(&self, c: u32, x: DVec3, u: DVec3) -> DVec3 {
        match &self.wall {
            None => u,
            Some(w) => w.apply(c, x, u),
        }
    }

    /// The mesh, m.
    pub fn mesh(&self) -> &PolyMesh {
        self.loc.mesh()
    }

    /// Its geometry.
    pub fn geometry(&self) -> &MeshGeometry {
        self.loc.geometry()
    }

    /// The locator.
    pub fn locator(&self) -> &Locator<'static> {
        &self.loc
    }

    /// The per-cell records of the hot path (`None` when the mesh was too large for them,
    /// [`CellTable::MAX_BYTES`]).
    pub fn table(&self) -> Option<&CellTable> {
        self.table.as_ref()
    }

    /// Bytes this flow holds of its own (its interpolator's values and its tracker
    /// table; the mesh and locator, which snapshots of a series share, not counted).
    pub fn bytes(&self) -> usize {
        self.interp.bytes() + self.table.as_ref().map_or(0, CellTable::bytes)
    }

    /// The interpolation scheme.
    pub fn scheme(&self) -> Interpolation {
        self.interp.scheme()
    }

    /// What the conservative scheme's projection changed (`None` for the other schemes).
    pub fn projection(&self) -> Option<&scg_mesh::conservative::Projection> {
        self.interp.projection()
    }

    /// Role of every patch (same order as the mesh's patches).
    pub fn roles(&self) -> &[PatchRole] {
        &self.roles
    }

    /// Smallest and largest speed of the cell values, m/s.
    pub fn field_speed(&self) -> (f64, f64) {
        self.field_speed
    }

    /// Role of patch `p` (an unknown patch is lost).
    #[inline]
    pub fn role(&self, p: u32) -> PatchRole {
        self.roles
            .get(p as usize)
            .copied()
            .unwrap_or(PatchRole::Lost)
    }

    /// The cell holding x (grid search), `None` outside the mesh.
    pub fn find_cell(&self, x: DVec3) -> Option<u32> {
        self.loc.find_cell(x)
    }

    /// Locate x walking from cell `hint` (any value: a marker or a stale cell falls back to
    /// the grid).
    #[inline]
    pub fn track(&self, hint: u32, x: DVec3) -> Location {
        self.loc.track(hint, x)
    }

    /// The interpolated velocity at x when x is in cell `c` (checked with the
    /// [`CellTable`] alone; `None` when it is not, or when that cannot tell), m/s.
    #[inline]
    pub fn velocity_in(&self, c: u32, x: DVec3) -> Option<DVec3> {
        self.table.as_ref()?.velocity_in(c, x)
    }

    /// Where x is, found from cell `c` with the [`CellTable`] alone across at most
    /// [`TABLE_HOPS`] faces: the cell holding x and the interpolated velocity there (m/s),
    /// or the boundary face the walk meets; [`TableWalk::Unknown`] when the table cannot
    /// tell (then walk with [`MeshFlow::track`]).
    #[inline]
    pub fn walk_table(&self, c: u32, x: DVec3) -> TableWalk {
        self.walk_from(Place::cell(c), x)
    }

    /// [`MeshFlow::walk_table`] from `place`, its tetrahedron the first tried (a hint:
    /// the same answer, bit for bit, [`CellTable::walk`]).
    #[inline]
    pub fn walk_from(&self, place: Place, x: DVec3) -> TableWalk {
        match &self.table {
            Some(t) => t.walk(place.cell, place.tet, x, TABLE_HOPS),
            None => TableWalk::Unknown,
        }
    }

    /// The patch of boundary face `f` (`u32::MAX` for an internal face).
    #[inline]
    pub fn patch_of(&self, f: u32) -> u32 {
        self.loc.patch_of(f)
    }

    /// Interpolated velocity where a point was found, m/s.
    #[inline]
    pub fn at(&self, hit: &Hit) -> DVec3 {
        self.interp.at(hit)
    }

    /// Fluid velocity at x (m/s) for a particle whose last cell is `hint` (x inside the
    /// mesh or close to it), and the cell to use as the next hint. Where x is outside the
    /// mesh the value is extrapolated from the hint's cell ([`Interpolator::velocity`]).
    #[inline]
    pub fn velocity(&self, hint: u32, x: DVec3) -> (DVec3, u32) {
        let (u, p) = self.velocity_at(Place::cell(hint), x);
        (u, p.cell)
    }

    /// [`MeshFlow::velocity`] from `place` (its tetrahedron a hint), and where x is: its
    /// cell and, when the table found it, its tetrahedron.
    #[inline]
    pub fn velocity_at(&self, place: Place, x: DVec3) -> (DVec3, Place) {
        let hint = place.cell;
        let hit = match self.walk_from(place, x) {
            TableWalk::Inside { cell, tet, value } => {
                return (self.near_wall(cell, x, value), Place { cell, tet });
            }
            // The ray toward x leaves the mesh through a boundary face (a particle at a
            // wall, its mid-step point beyond it): the locator's walk, on the same faces,
            // would end there too, and only asks whether x is inside the mesh elsewhere (a
            // concave boundary, a thin wall). Ask that directly.
            TableWalk::Boundary { .. } => self.loc.find(x),
            TableWalk::Unknown => match self.loc.track(hint, x) {
                Location::Inside(h) | Location::Crossed { hit: h, .. } => Some(h),
                Location::Left { .. } | Location::Outside => None,
            },
        };
        match hit {
            Some(h) => {
                let u = self
                    .velocity_in(h.cell, x)
                    .unwrap_or_else(|| self.interp.at(&h));
                (self.near_wall(h.cell, x, u), Place::cell(h.cell))
            }
            None => (
                self.near_wall(hint, x, self.interp.velocity(hint, x)),
                Place::cell(hint),
            ),
        }
    }

    /// [`MeshFlow::velocity`] without the [`CellTable`] (the locator and the interpolator
    /// alone), m/s.
    pub fn velocity_walk(&self, hint: u32, x: DVec3) -> (DVec3, u32) {
        match self.loc.track(hint, x) {
            Location::Inside(h) | Location::Crossed { hit: h, .. } => {
                (self.near_wall(h.cell, x, self.interp.at(&h)), h.cell)
            }
            Location::Left { .. } | Location::Outside => {
                (self.near_wall(hint, x, self.interp.velocity(hint, x)), hint)
            }
        }
    }

    /// Ask the processor to load what locating a particle in cell `c` reads first: its
    /// [`CellTable`] record, when `deep` also its face records (which need the cell record
    /// in cache to be addressed); without a table, the cell centre and face list, when
    /// `deep` also the faces' centres and areas. Calling it a few particles ahead hides
    /// memory latency on large meshes; no effect on results.
    #[inline(always)]
    pub fn prefetch(&self, c: u32, deep: bool) {
        if let Some(t) = &self.table {
            t.prefetch(c, deep);
            return;
        }
        let g = self.loc.geometry();
        let m = self.loc.mesh();
        let ci = c as usize;
        if ci >= g.cell_centres.len() {
            return;
        }
        scg_mesh::prefetch::element(&g.cell_centres, ci);
        scg_mesh::prefetch::element(&g.cell_face_offsets, ci);
        if deep {
            let (a, b) = (
                g.cell_face_offsets[ci] as usize,
                g.cell_face_offsets[ci + 1] as usize,
            );
            scg_mesh::prefetch::element(&g.cell_faces, a);
            for &f in g.cell_faces.get(a..b).unwrap_or(&[]) {
                scg_mesh::prefetch::element(&g.face_areas, f as usize);
                scg_mesh::prefetch::element(&g.face_centres, f as usize);
                scg_mesh::prefetch::element(&m.face_offsets, f as usize);
            }
        }
    }

    /// Ask the processor to load tetrahedron record `tet` (a particle's hint) when there
    /// is one; false when `tet` names none. No effect on results.
    #[inline(always)]
    pub fn prefetch_tet(&self, tet: u32) -> bool {
        self.table.as_ref().is_some_and(|t| t.prefetch_tet(tet))
    }

    /// A snapshot of a series (its table a field's values on another's records): ask the
    /// processor to load tetrahedron `tet`'s values, some particles after
    /// [`MeshFlow::prefetch_tet`] ([`CellTable::prefetch_tet_values`]). No effect on results.
    #[inline(always)]
    pub fn prefetch_tet_values(&self, tet: u32) {
        if let Some(t) = &self.table {
            t.prefetch_tet_values(tet);
        }
    }

    /// Ask the processor to load the [`CellTable`] records a query for x in cell `c` reads
    /// last (the tetrahedron; the cell and face records should be in cache by then: call
    /// [`MeshFlow::prefetch`] earlier). No effect on results.
    #[inline(always)]
    pub fn prefetch_at(&self, c: u32, x: DVec3) {
        if let Some(t) = &self.table {
            t.prefetch_at(c, x);
        }
    }

    /// Unit outward normal and centre of boundary face `f`, m.
    #[inline]
    pub fn face_plane(&self, f: u32) -> (DVec3, DVec3) {
        let g = self.loc.geometry();
        let n = g.face_areas[f as usize].normalize_or_zero();
        (n, g.face_centres[f as usize])
    }
}

/// Most interior faces [`MeshFlow::walk_table`] crosses before it leaves the search to the
/// locator (whose walk reads far more memory per cell, and knows the boundary).
pub const TABLE_HOPS: usize = 4;

mod balance;
mod gradient;
mod landing;
pub mod moving;
pub mod series;
#[cfg(test)]
mod tests;
