//! Reading gmsh MSH 4.1 files (ASCII and binary) into a [`peritherm_core::mesh::Mesh`].
//!
//! The format is specified in the gmsh reference manual, section "MSH file format"
//! (<https://gmsh.info/doc/texinfo/gmsh.html#MSH-file-format>). The `$Entities`, `$Nodes` and
//! `$Elements` sections are decoded by the `mshio` crate. `$MeshFormat` is checked here first
//! (mshio panics on some headers), and `$PhysicalNames`, which mshio skips, is read here from
//! its text (it is text in binary files too). Only elements of physical groups are kept.
//!
//! When node tags are dense (`maxTag − minTag + 1 = numNodes`) mshio drops them, so node `t`
//! is taken to be the `(t − minTag)`-th node in file order, which is how gmsh writes them.

use std::collections::{BTreeMap, HashMap};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

use mshio::{ElementType, MshFile, MshParserError};

use crate::error::{Error, Result};
use peritherm_core::math::Point;
use peritherm_core::mesh::{integrity, Element, ElementKind, Group, Mesh};

/// Physical group names by (dimension, tag).
type Names = BTreeMap<(i32, i32), String>;
type Msg<T> = std::result::Result<T, String>;

const RESAVE: &str = "re-save it as MSH 4.1, e.g. `gmsh FILE -save -format msh41` or \
                      `Mesh.MshFileVersion = 4.1;` in the .geo";
const REGENERATE: &str = "regenerate it with gmsh";
const UNSUPPORTED: &str = "is not supported: mesh with first-order elements \
    (Mesh.ElementOrder = 1) and triangles/quadrangles/tetrahedra/hexahedra";
const NO_GROUPS: &str = "has no physical groups: add `Physical Surface(\"name\") = {...};` (and \
                         curves for boundaries) in the .geo and mesh again";

/// Reads a gmsh MSH 4.1 file (ASCII or binary).
pub fn read(path: &Path) -> Result<Mesh> {
    let bytes = std::fs::read(path).map_err(|e| fail(path, format!("cannot read it: {e}")))?;
    parse(&bytes, path)
}

/// Parses MSH 4.1 bytes; `path` is only used in error messages.
pub fn parse(bytes: &[u8], path: &Path) -> Result<Mesh> {
    parse_bytes(bytes).map_err(|m| fail(path, m))
}

fn parse_bytes(bytes: &[u8]) -> Msg<Mesh> {
    let binary = check_header(bytes)?;
    // mshio computes `count − 1` on these counts, which overflows (a panic in debug builds) on 0.
    for (section, what) in [("$Nodes", "nodes"), ("$Elements", "elements")] {
        if section_count(bytes, section, binary) == Some(0) {
            return Err(no_mesh(what));
        }
    }
    let parsed = catch_unwind(AssertUnwindSafe(|| mshio::parse_msh_bytes(bytes)))
        .map_err(|_| format!("the mesh could not be decoded (mshio panicked); {REGENERATE}"))?
        .map_err(|e| {
            let why = summary(bytes, &e);
            format!("the mesh is truncated or malformed (mshio: {why}); {REGENERATE}")
        })?;
    let tags = node_tags(bytes, binary)?;
    let (mesh, element_tags) = build(&parsed, physical_names(bytes)?, &tags)?;
    validate(&mesh, &tags, &element_tags)?;
    Ok(mesh)
}

/// Refuses a mesh with a defect of [`integrity::validate`], naming the elements by their tags.
fn validate(mesh: &Mesh, node_tags: &[u64], element_tags: &[u64]) -> Msg<()> {
    integrity::validate(mesh).map_err(|d| {
        let tag = |e: usize| element_tags[e];
        let node = |n: usize| node_tags[n];
        d.describe(mesh, &tag, &node)
    })
}

fn fail(path: &Path, message: String) -> Error {
    Error::Mesh {
        path: path.to_path_buf(),
        message,
    }
}

fn no_mesh(what: &str) -> String {
    format!(
        "has no {what}: mesh the geometry (e.g. `gmsh -2 FILE.geo` or Mesh.Generate) before saving"
    )
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

/// The line starting at `at` (trimmed) and the offset after its line break, if it has one.
fn line_at(bytes: &[u8], at: usize) -> Option<(&str, usize)> {
    let rest = bytes.get(at..)?;
    let end = rest.iter().position(|&b| b == b'\n')?;
    Some((std::str::from_utf8(&rest[..end]).ok()?.trim(), at + end + 1))
}

/// Checks `$MeshFormat`; returns `None` for ASCII, `Some(little_endian)` for binary.
fn check_header(bytes: &[u8]) -> Msg<Option<bool>> {
    let start = find(bytes, b"$MeshFormat").ok_or_else(|| {
        "not a gmsh mesh file (no `$MeshFormat` header); give a .msh file written by gmsh"
            .to_string()
    })?;
    let truncated = || format!("the `$MeshFormat` header is truncated; {REGENERATE}");
    let (_, first) = line_at(bytes, start).ok_or_else(truncated)?;
    let (line, next) = line_at(bytes, first).ok_or_else(truncated)?;
    let echo = |text: &str| text.escape_debug().to_string();
    let [version, file_type, data_size] = line.split_whitespace().collect::<Vec<_>>()[..] else {
        return Err(format!(
            "the `$MeshFormat` line `{}` is not `version file-type data-size`; {REGENERATE}",
            echo(line)
        ));
    };
    if version.parse::<f64>().ok() != Some(4.1) {
        return Err(format!(
            "the file is MSH {}, but peritherm reads MSH 4.1 only: {RESAVE}",
            echo(version)
        ));
    }
    if data_size.parse::<u64>().ok() != Some(8) {
        return Err(format!(
            "data-size {} in `$MeshFormat` is not supported (gmsh writes 8); {REGENERATE}",
            echo(data_size)
        ));
    }
    let marker = bytes.get(next..).and_then(|b| b.get(..4));
    match (file_type, marker) {
        ("0", _) => Ok(None),
        ("1", Some([1, 0, 0, 0])) => Ok(Some(true)),
        ("1", Some([0, 0, 0, 1])) => Ok(Some(false)),
        ("1", _) => Err(format!(
            "the binary header lacks its endianness marker; {REGENERATE}"
        )),
        _ => Err(format!(
            "file-type {} is neither 0 (ASCII) nor 1 (binary); {REGENERATE}",
            echo(file_type)
        )),
    }
}

/// The second number of a section's header (its node or element count), if readable.
fn section_count(bytes: &[u8], section: &str, binary: Option<bool>) -> Option<u64> {
    let at = find(bytes, format!("\n{section}").as_bytes())? + section.len() + 1;
    let (_, at) = line_at(bytes, at)?;
    let Some(little) = binary else {
        return line_at(bytes, at)?
            .0
            .split_whitespace()
            .nth(1)?
            .parse()
            .ok();
    };
    let count = u64::from_le_bytes(bytes.get(at + 8..at + 16)?.try_into().ok()?);
    Some(if little { count } else { count.swap_bytes() })
}

/// One line from a mshio error: where (byte, outermost context) and what (≤ 120 chars).
fn summary(bytes: &[u8], error: &MshParserError<&[u8]>) -> String {
    let trace = error.filtered_backtrace();
    let Some((rest, kind)) = trace.first() else {
        return "unknown error".into();
    };
    let what = kind
        .context()
        .map_or(kind.to_string(), |c| format!("cannot read the {c}"));
    let mut text = format!("at byte {}", bytes.len().saturating_sub(rest.len()));
    if let Some(section) = trace
        .iter()
        .skip(1)
        .filter_map(|(_, k)| k.context())
        .next_back()
    {
        text += &format!(" in the {section}");
    }
    text += &format!(": {}", what.trim_end_matches('.'));
    let text = text.split_whitespace().collect::<Vec<_>>().join(" ");
    match text.char_indices().nth(119) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text,
    }
}

/// Parses `$PhysicalNames` (`count`, then lines `dim tag "name"`), if present.
fn physical_names(bytes: &[u8]) -> Msg<Names> {
    let mut names = Names::new();
    let Some(start) = find(bytes, b"$PhysicalNames") else {
        return Ok(names);
    };
    let bad =
        |what: &str| format!("the `$PhysicalNames` section is malformed ({what}); {REGENERATE}");
    let end = start + find(&bytes[start..], b"$EndPhysicalNames").ok_or_else(|| bad("no end"))?;
    let text = std::str::from_utf8(&bytes[start..end]).map_err(|_| bad("not text"))?;
    let mut lines = text
        .lines()
        .skip(1)
        .map(str::trim)
        .filter(|l| !l.is_empty());
    let count = lines.next().and_then(|l| l.parse::<usize>().ok());
    let count = count.ok_or_else(|| bad("no count"))?;
    for line in lines {
        let entry = line.split_once('"').and_then(|(head, rest)| {
            let name = rest.strip_suffix('"')?;
            let (dim, tag) = head.trim().split_once(char::is_whitespace)?;
            let dim = dim.parse().ok().filter(|d| (0..=3).contains(d))?;
            Some(((dim, tag.trim().parse().ok()?), name.to_string()))
        });
        let (key, name) = entry.ok_or_else(|| bad(&format!("line `{}`", line.escape_debug())))?;
        names.insert(key, name);
    }
    match names.len() {
        n if n == count => Ok(names),
        n => Err(bad(&format!("{count} names announced, {n} found"))),
    }
}

/// The peritherm shape of a gmsh element type, if it is supported.
fn kind_of(t: ElementType) -> Option<ElementKind> {
    Some(match t {
        ElementType::Pnt => ElementKind::Point,
        ElementType::Lin2 => ElementKind::Line,
        ElementType::Tri3 => ElementKind::Triangle,
        ElementType::Qua4 => ElementKind::Quad,
        ElementType::Tet4 => ElementKind::Tet,
        ElementType::Hex8 => ElementKind::Hex,
        _ => return None,
    })
}

/// The mshio file type this reader parses.
type Msh = MshFile<u64, i32, f64>;

/// Assembles the mesh from mshio's sections, the physical names and the node tags in file
/// order; returns it with the tag of every element.
fn build(msh: &Msh, mut names: Names, tags: &[u64]) -> Msg<(Mesh, Vec<u64>)> {
    let entity_groups = entity_groups(msh, &mut names);
    let groups = GroupTable::new(names)?;
    let nodes = NodeTable::read(msh, tags)?;
    let (elements, element_tags) = read_elements(msh, &entity_groups, &groups, &nodes)?;
    if elements.is_empty() {
        return Err(no_mesh("elements in its physical groups"));
    }
    let mesh = Mesh {
        nodes: nodes.nodes,
        elements,
        groups: groups.groups,
    };
    Ok((mesh, element_tags))
}

/// The physical tags of every (dimension, entity tag) of `$Entities`; every physical tag
/// without a name in `names` gets its number as name.
fn entity_groups<'a>(msh: &'a Msh, names: &mut Names) -> HashMap<(i32, i32), &'a [i32]> {
    let mut entity_groups: HashMap<(i32, i32), &[i32]> = HashMap::new();
    if let Some(e) = &msh.data.entities {
        let all = (e.points.iter().map(|p| (0, p.tag, &p.physical_tags)))
            .chain(e.curves.iter().map(|c| (1, c.tag, &c.physical_tags)))
            .chain(e.surfaces.iter().map(|s| (2, s.tag, &s.physical_tags)))
            .chain(e.volumes.iter().map(|v| (3, v.tag, &v.physical_tags)));
        for (dim, tag, physical) in all {
            for &p in physical {
                names.entry((dim, p)).or_insert_with(|| p.to_string());
            }
            entity_groups.insert((dim, tag), physical);
        }
    }
    entity_groups
}

/// The physical groups in (dimension, tag) order and the index of each.
struct GroupTable {
    /// Index in `groups` of each (dimension, physical tag).
    index: HashMap<(i32, i32), u16>,
    groups: Vec<Group>,
}

impl GroupTable {
    /// The table of the named groups; an error when there is none, more than 65536, or two of
    /// one dimension with one name.
    fn new(names: Names) -> Msg<GroupTable> {
        if names.is_empty() {
            return Err(NO_GROUPS.into());
        }
        let mut by_name: HashMap<(i32, &str), i32> = HashMap::new();
        for (&(dim, tag), name) in &names {
            if let Some(first) = by_name.insert((dim, name.as_str()), tag) {
                return Err(format!(
                    "physical groups {first} and {tag} of dimension {dim} are both named `{}`, so \
                     a boundary or region of that name is ambiguous: rename one, or make them \
                     one group",
                    name.escape_debug()
                ));
            }
        }
        let index: HashMap<(i32, i32), u16> = names.keys().copied().zip(0..=u16::MAX).collect();
        if index.len() < names.len() {
            return Err("has more than 65536 physical groups".into());
        }
        let to_group = |((dim, tag), name): ((i32, i32), String)| Group {
            dim: dim as usize,
            tag,
            name,
        };
        let groups: Vec<Group> = names.into_iter().map(to_group).collect();
        Ok(GroupTable { index, groups })
    }
}

/// The nodes of `$Nodes` and how a node tag finds its index.
struct NodeTable {
    nodes: Vec<Point>,
    /// Index of each tag when the tags are not consecutive in file order.
    sparse: HashMap<u64, usize>,
    /// True when node tags run from `min_tag` in file order.
    dense: bool,
    min_tag: u64,
}

impl NodeTable {
    /// Reads every node block with `tags`, the node tags in file order ([`node_tags`]); an
    /// error when there is no node or a tag appears twice.
    fn read(msh: &Msh, tags: &[u64]) -> Msg<NodeTable> {
        let blocks = msh.data.nodes.iter().flat_map(|n| &n.node_blocks);
        let nodes: Vec<Point> = blocks
            .flat_map(|b| b.nodes.iter().map(|n| Point::new(n.x, n.y, n.z)))
            .collect();
        if nodes.is_empty() {
            return Err(no_mesh("nodes"));
        }
        if tags.len() != nodes.len() {
            return Err(format!(
                "the `$Nodes` section lists {} tags for {} nodes; {REGENERATE}",
                tags.len(),
                nodes.len()
            ));
        }
        let min_tag = tags[0];
        let dense = tags
            .iter()
            .enumerate()
            .all(|(i, &t)| Some(t) == min_tag.checked_add(i as u64));
        let mut sparse = HashMap::new();
        if !dense {
            sparse.reserve(tags.len());
            for (i, &t) in tags.iter().enumerate() {
                if sparse.insert(t, i).is_some() {
                    return Err(format!(
                        "node tag {t} appears twice in `$Nodes`, so the elements that name it \
                         are ambiguous; {REGENERATE}"
                    ));
                }
            }
        }
        Ok(NodeTable {
            nodes,
            sparse,
            dense,
            min_tag,
        })
    }

    /// The index of the node tagged `tag`, `None` when `$Nodes` lacks it.
    fn index(&self, tag: u64) -> Option<u32> {
        let i = match self.dense {
            true => usize::try_from(tag.checked_sub(self.min_tag)?).ok()?,
            false => *self.sparse.get(&tag)?,
        };
        u32::try_from(i).ok().filter(|_| i < self.nodes.len())
    }
}

/// A reader of the numbers of a section, ASCII or binary (`Some(little_endian)`).
struct Numbers<'a> {
    bytes: &'a [u8],
    at: usize,
    binary: Option<bool>,
}

impl Numbers<'_> {
    /// The next ASCII token.
    fn token(&mut self) -> Option<&[u8]> {
        let rest = self.bytes.get(self.at..)?;
        let start = rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let len = rest[start..]
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len() - start);
        self.at += start + len;
        Some(&rest[start..start + len])
    }

    /// The next `width` bytes (binary).
    fn raw<const W: usize>(&mut self) -> Option<[u8; W]> {
        let b = self.bytes.get(self.at..self.at + W)?.try_into().ok()?;
        self.at += W;
        Some(b)
    }

    /// The next integer: an ASCII token, or a binary `int` (`wide` false) or `size_t`.
    fn int(&mut self, wide: bool) -> Option<u64> {
        let Some(little) = self.binary else {
            return std::str::from_utf8(self.token()?).ok()?.parse().ok();
        };
        let v = match wide {
            true => self.raw::<8>().map(|b| {
                if little {
                    u64::from_le_bytes(b)
                } else {
                    u64::from_be_bytes(b)
                }
            })?,
            false => self.raw::<4>().map(|b| {
                if little {
                    i32::from_le_bytes(b)
                } else {
                    i32::from_be_bytes(b)
                }
            })? as u64,
        };
        Some(v)
    }

    /// Skips `n` numbers of 8 bytes (binary) or `n` tokens (ASCII).
    fn skip(&mut self, n: u64) -> Option<()> {
        match self.binary {
            Some(_) => {
                self.at = self
                    .at
                    .checked_add(usize::try_from(n).ok()?.checked_mul(8)?)?;
                (self.at <= self.bytes.len()).then_some(())
            }
            None => (0..n).try_for_each(|_| self.token().map(|_| ())),
        }
    }
}

/// The node tags of `$Nodes` in file order (mshio drops them when they look consecutive, so a
/// repeated or permuted tag would go unseen).
fn node_tags(bytes: &[u8], binary: Option<bool>) -> Msg<Vec<u64>> {
    let bad = || format!("the `$Nodes` section is malformed; {REGENERATE}");
    let start = find(bytes, b"\n$Nodes").ok_or_else(|| no_mesh("nodes"))?;
    let (_, at) = line_at(bytes, start + 1).ok_or_else(bad)?;
    let mut r = Numbers { bytes, at, binary };
    let header: Option<[u64; 4]> =
        (|| Some([r.int(true)?, r.int(true)?, r.int(true)?, r.int(true)?]))();
    let [blocks, count, _, _] = header.ok_or_else(bad)?;
    let mut tags = Vec::with_capacity(usize::try_from(count).unwrap_or(0).min(bytes.len() / 8));
    for _ in 0..blocks {
        let block = (|| {
            let dim = r.int(false)?;
            let _entity = r.int(false)?;
            let parametric = r.int(false)?;
            let n = r.int(true)?;
            // x y z, and u (v, w) up to the entity's dimension when parametric
            let per_node = 3 + if parametric == 1 { dim.min(3) } else { 0 };
            (parametric <= 1).then_some((n, per_node))
        })();
        let (n, per_node) = block.ok_or_else(bad)?;
        for _ in 0..n {
            tags.push(r.int(true).ok_or_else(bad)?);
        }
        r.skip(n.checked_mul(per_node).ok_or_else(bad)?)
            .ok_or_else(bad)?;
    }
    Ok(tags)
}

/// The supported elements of the entities that belong to a physical group, each with its
/// groups, and their tags; an error for an unsupported type, a type of the wrong dimension or
/// a missing node.
fn read_elements(
    msh: &Msh,
    entity_groups: &HashMap<(i32, i32), &[i32]>,
    groups: &GroupTable,
    nodes: &NodeTable,
) -> Msg<(Vec<Element>, Vec<u64>)> {
    let (mut elements, mut tags) = (Vec::new(), Vec::new());
    for block in msh.data.elements.iter().flat_map(|e| &e.element_blocks) {
        let (dim, t) = (block.entity_dim, block.element_type);
        let Some(physical) = entity_groups.get(&(dim, block.entity_tag)) else {
            continue;
        };
        let member: std::sync::Arc<[u16]> = physical
            .iter()
            .filter_map(|p| groups.index.get(&(dim, *p)).copied())
            .collect();
        let Some(group) = member.first().map(|&g| &groups.groups[usize::from(g)].name) else {
            continue;
        };
        let unsupported = || {
            let code = t as i32;
            format!(
                "element type {t:?} (gmsh type {code}) in physical group `{group}` {UNSUPPORTED}"
            )
        };
        let kind = kind_of(t).ok_or_else(unsupported)?;
        if kind.dim() as i32 != dim {
            return Err(format!("{t:?} elements on a {dim}D entity; {REGENERATE}"));
        }
        for e in &block.elements {
            let tag = e.element_tag;
            let lacks =
                |n| format!("element {tag} refers to node {n}, which `$Nodes` lacks; {REGENERATE}");
            let nodes = e
                .nodes
                .iter()
                .map(|&n| nodes.index(n).ok_or_else(|| lacks(n)));
            let nodes = nodes.collect::<Msg<_>>()?;
            elements.push(Element {
                kind,
                nodes,
                groups: member.clone(),
            });
            tags.push(tag);
        }
    }
    elements.shrink_to_fit();
    tags.shrink_to_fit();
    Ok((elements, tags))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One triangle on surface 1 of physical group 7 (no name), nodes tagged 10, 20, 30.
    const SPARSE: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 1 0\n\
        1 0 0 0 1 1 0 1 7 0\n$EndEntities\n$Nodes\n1 3 10 30\n2 1 0 3\n10\n20\n30\n\
        0 0 0\n1 0 0\n0 1 0\n$EndNodes\n$Elements\n1 1 1 1\n2 1 2 1\n1 30 10 20\n$EndElements\n";

    fn message(text: &str) -> String {
        parse(text.as_bytes(), Path::new("t.msh"))
            .expect_err("refused")
            .to_string()
    }

    // Sparse node tags map to file order; a group without a name is named by its tag.
    #[test]
    fn sparse_tags_and_unnamed_groups() {
        let mesh = parse(SPARSE.as_bytes(), Path::new("t.msh")).expect("valid");
        assert_eq!(mesh.elements[0].nodes, [2, 0, 1]);
        assert_eq!(mesh.nodes[2], Point::new(0.0, 1.0, 0.0));
        assert_eq!(
            mesh.groups,
            [Group {
                dim: 2,
                tag: 7,
                name: "7".into()
            }]
        );
    }

    // Unknown node tags, zero counts (an overflow inside mshio) and bad headers are refused.
    #[test]
    fn inconsistent_files_are_refused() {
        assert!(message(&SPARSE.replace("1 30 10 20", "1 30 10 40")).contains("node 40"));
        let empty = SPARSE.replace("1 3 10 30\n2 1 0 3\n10\n20\n30", "1 0 10 10\n2 1 0 0");
        assert!(message(&empty).contains("no nodes"));
        assert!(message(&SPARSE.replace("4.1 0 8", "4.1 0 99999999999")).contains("data-size"));
        assert!(message(&SPARSE.replace("4.1 0 8", "4.0 0 8")).contains("MSH 4.0"));
        let names = SPARSE.replace(
            "$Entities",
            "$PhysicalNames\n2\n2 7 \"a\"\n$EndPhysicalNames\n$Entities",
        );
        assert!(message(&names).contains("2 names announced, 1 found"));
    }

    // Node tags come from the file, not from mshio (which drops them when they look
    // consecutive): a repeated tag is refused, whether the tags look dense or sparse, and a
    // permuted dense list maps by tag.
    #[test]
    fn node_tags_are_read_from_the_file() {
        let repeated = SPARSE.replace("10\n20\n30", "10\n20\n10");
        assert!(message(&repeated).contains("node tag 10 appears twice"));
        let dense = SPARSE
            .replace("1 3 10 30", "1 3 1 3")
            .replace("10\n20\n30", "1\n2\n3");
        let dense = dense.replace("1 30 10 20", "1 3 1 2");
        let mesh = parse(dense.as_bytes(), Path::new("t.msh")).expect("valid");
        assert_eq!(mesh.elements[0].nodes, [2, 0, 1]);
        assert!(message(&dense.replace("1\n2\n3", "1\n2\n2")).contains("node tag 2 appears twice"));
        let permuted = parse(
            dense.replace("1\n2\n3", "3\n1\n2").as_bytes(),
            Path::new("t.msh"),
        );
        assert_eq!(permuted.expect("valid").elements[0].nodes, [0, 1, 2]);
    }

    // Two physical groups of one dimension with one name are refused; of two dimensions, not.
    #[test]
    fn one_name_for_two_groups_of_one_dimension_is_refused() {
        let two = |d: i32| {
            let names =
                format!("$PhysicalNames\n2\n2 7 \"a\"\n{d} 8 \"a\"\n$EndPhysicalNames\n$Entities");
            SPARSE.replace("$Entities", &names)
        };
        let m = message(&two(2));
        assert!(
            m.contains("physical groups 7 and 8 of dimension 2 are both named `a`"),
            "{m}"
        );
        assert!(parse(two(1).as_bytes(), Path::new("t.msh")).is_ok());
    }
}
