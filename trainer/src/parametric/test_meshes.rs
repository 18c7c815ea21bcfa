//! Meshes the parametric tests build: quads of an index grid, two triangles each.

/// The triangles of the quads (i, j)–(i + 1, j + 1) for i in `columns`, j in `rows`, with
/// `id` naming each grid vertex (wrap indices there for a closed direction).
pub fn quad_triangles(
    rows: std::ops::Range<usize>,
    columns: std::ops::Range<usize>,
    id: impl Fn(usize, usize) -> u32,
) -> Vec<[u32; 3]> {
    let mut triangles = Vec::new();
    for j in rows {
        for i in columns.clone() {
            triangles.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
            triangles.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
        }
    }
    triangles
}
