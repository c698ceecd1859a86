//! The Mitsuba 3 XML importer: a Mitsuba 3 scene file (`<scene version="3.0.0">`) translated
//! into an authored luxest scene. The parsing follows Mitsuba 3's `src/core/parser.cpp`;
//! the plugins follow their documentation in Mitsuba 3's `src/<kind>/<plugin>.cpp`.
//!
//! **Parsing.** `<default name value>` defines `$name` where it is not yet defined, and every
//! attribute's `$name` is replaced (longest names first; `\$` escapes); an undefined `$name`
//! is an error. `<include filename>` inserts another file's elements (its `<scene>` root
//! dropped), resolved against the including file's directory; a file that includes itself,
//! directly or not, is an error. `<ref id>` refers to an object with that `id` (`name` gives
//! the property name); `<alias id as>` gives an object a second id. Scenes of version < 2.0
//! get Mitsuba's upgrade: camelCase property names become snake_case (`toWorld` →
//! `to_world`), a `diffuse`'s `diffuse_reflectance` becomes `reflectance`, and a bitmap's
//! `uoffset`, `voffset`, `uscale`, `vscale` become its `to_uv`.
//!
//! **Properties.** `float`, `integer`, `boolean`, `string`, `rgb` (one or three values),
//! `spectrum` (a single constant value only), `point`, `vector` and `transform` (`matrix` of 9
//! or 16 values, `lookat`, `translate`, `rotate` (axis and angle in degrees), `scale`,
//! composed in order: each applies after the previous ones). A property the translation does
//! not read is an error, so nothing is dropped without a word.
//!
//! **Objects.** Shapes `obj`, `ply`, `serialized` (versions 3 and 4), `rectangle`, `cube`, `sphere`, `disk` (with `to_world`,
//! `flip_normals`, `face_normals`; vertex normals computed as Mitsuba computes them for mesh
//! files without, [`crate::shapes::angle_weighted_normals`]); BSDFs `diffuse`, `dielectric`, `thindielectric`,
//! `roughdielectric`, `conductor` and `roughconductor` (`eta`/`k`, or a `material` preset of
//! [`super::mitsuba_tables`]; `none`, smooth, is luxest's `Mirror`), `plastic`,
//! `roughplastic`, `blendbsdf` (constant weight), `twosided`, `mask`, `normalmap` (its
//! texture the surface's normal map, with Mitsuba's default flags; outside `twosided`, not
//! inside it); a BSDF not inside
//! `twosided` is one-sided (a surface with `two_sided: false`), and a shape without one gets
//! Mitsuba's default (a one-sided diffuse 0.5); `bitmap` textures as the main colour, a rough
//! BSDF's α, a mask's opacity and an area emitter's radiance; emitters `area` (inside a shape),
//! `point`, `spot`, `constant`, `envmap` (OpenEXR); sensor `perspective` (`fov`, `fov_axis`,
//! `focal_length`, `to_world`) with film `hdrfilm` (`width`, `height`). `<integrator>` and the
//! sensor's `<sampler>` are left out with a warning (luxest's estimator and sample count are
//! chosen on its command line), a non-box `<rfilter>` likewise (luxest's pixel filter is a
//! box). Anything else is an error naming the file, the line and the element.
//!
//! **Units.** Mitsuba's RGB radiance (area, constant and environment emitters) becomes luxest's
//! luminance in cd/m² with the same numbers, and its point intensity luxest's candela; luxest
//! is an RGB renderer whose photometric quantity is the RGB luminance Y.

use crate::import::{scene_relative, Imported};
use luxest_io::color::Rgb;
use luxest_io::math::{Affine, Vec3};
use luxest_io::{Error, Result};
use luxest_render::scene::{
    Camera, Emission, Environment, Material, Microfacet, MicrofacetDistribution, Object, Opacity,
    OpacityChannel, PointLight, PointPower, Scene, Shape, Spot, Surface, TextureDesc, Transform,
};
use luxest_render::texture::{Encoding, Filter, UvTransform, Wrap};
use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Icosphere subdivision level of a Mitsuba `sphere` (20 · 4^6 = 81920 triangles: its area is
/// the sphere's to 1e-4 relative).
pub const SPHERE_SUBDIVISIONS: u32 = 6;
/// Vertices of the polygon a Mitsuba `disk` becomes (its radius scaled so that its area is the
/// disk's).
pub const DISK_SEGMENTS: usize = 256;
/// Deepest `<include>` nesting, as Mitsuba's default `max_include_depth`.
const MAX_INCLUDE_DEPTH: usize = 15;
/// Deepest nesting of elements in one file, and of BSDFs through references (a `<ref>` to an
/// enclosing BSDF is a cycle): real scenes nest a few levels.
const MAX_NESTING: usize = 64;

/// One XML element after `$` substitution and `<include>` expansion.
#[derive(Clone, Debug)]
struct Elem {
    tag: String,
    attrs: Vec<(String, String)>,
    children: Vec<Elem>,
    /// Index into [`Parser::files`].
    file: usize,
    line: u32,
}

impl Elem {
    fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// The first pass: files read, parameters substituted, includes expanded.
struct Parser {
    files: Vec<PathBuf>,
    /// Per file: whether its version is below 2.0 (Mitsuba 0.x syntax, upgraded).
    legacy: Vec<bool>,
    /// `$name` → value, in definition order.
    params: Vec<(String, String)>,
    /// The files being read, outermost first (for recursion).
    stack: Vec<PathBuf>,
}

/// Where an element is, for messages: `line 12: <bsdf type="foo">`.
fn describe(e: &Elem) -> String {
    let mut s = format!("line {}: <{}", e.line, e.tag);
    for key in ["type", "id", "name"] {
        if let Some(v) = e.attr(key) {
            s.push_str(&format!(" {key}=\"{v}\""));
        }
    }
    s.push('>');
    s
}

fn camel_to_snake(s: &str) -> String {
    let chars: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len() + 4);
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if i > 0 && chars[i - 1].is_ascii_lowercase() && c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
            while i + 1 < chars.len() && chars[i + 1].is_ascii_uppercase() {
                i += 1;
                out.push(chars[i].to_ascii_lowercase());
            }
        } else {
            out.push(c);
        }
        i += 1;
    }
    out
}

/// Mitsuba's version string `major.minor.patch` as numbers.
fn parse_version(v: &str) -> Option<(u32, u32, u32)> {
    let mut it = v.trim().split('.').map(|p| p.parse::<u32>().ok());
    let major = it.next()??;
    let minor = it.next().unwrap_or(Some(0))?;
    let patch = it.next().unwrap_or(Some(0))?;
    Some((major, minor, patch))
}

impl Parser {
    fn fail(&self, file: usize, line: u32, msg: impl Into<String>) -> Error {
        Error::at(&self.files[file], format!("line {line}"), msg)
    }

    /// Reads `path` (included from `from`, when it is) into its root element.
    fn parse_file(&mut self, path: &Path, from: Option<(usize, u32)>) -> Result<Elem> {
        self.parse_file_bytes(path, None, from)
    }

    /// [`Parser::parse_file`] of the content `given` when given, else of the file.
    fn parse_file_bytes(
        &mut self,
        path: &Path,
        given: Option<&[u8]>,
        from: Option<(usize, u32)>,
    ) -> Result<Elem> {
        let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        if let Some((file, line)) = from {
            if self.stack.contains(&canonical) {
                return Err(self.fail(
                    file,
                    line,
                    format!(
                        "<include filename=\"{}\">: recursive include (the file includes itself, \
                         directly or through others)",
                        path.display()
                    ),
                ));
            }
            if self.stack.len() >= MAX_INCLUDE_DEPTH {
                return Err(self.fail(
                    file,
                    line,
                    format!("<include>: nested deeper than {MAX_INCLUDE_DEPTH} files"),
                ));
            }
            if !path.is_file() {
                return Err(self.fail(
                    file,
                    line,
                    format!("<include>: file {} not found", path.display()),
                ));
            }
        }
        let read;
        let bytes = match given {
            Some(b) => b,
            None => {
                read = luxest_io::fsio::read_bytes(path)?;
                &read[..]
            }
        };
        let text = std::str::from_utf8(bytes)
            .map_err(|_| Error::input(path, "not a Mitsuba XML file: not UTF-8 text"))?;
        let doc = roxmltree::Document::parse(text).map_err(|e| {
            let pos = e.pos();
            Error::at(
                path,
                format!("line {}", pos.row),
                format!("malformed XML: {e}"),
            )
        })?;
        let file = self.files.len();
        self.files.push(path.to_path_buf());
        self.stack.push(canonical);
        let root = doc.root_element();
        let line = doc.text_pos_at(root.range().start).row;
        let Some(version) = root.attribute("version") else {
            return Err(self.fail(
                file,
                line,
                format!(
                    "<{}>: the root element has no version attribute (a Mitsuba 3 scene starts \
                     with <scene version=\"3.0.0\">)",
                    root.tag_name().name()
                ),
            ));
        };
        let Some(version) = parse_version(version) else {
            return Err(self.fail(file, line, format!("invalid version \"{version}\"")));
        };
        let upgrade = version < (2, 0, 0);
        self.legacy.push(upgrade);
        let elem = self.convert(&doc, root, file, upgrade)?;
        self.stack.pop();
        Ok(elem.expect("the root is an element that stays"))
    }

    /// `$name` substitution in one attribute value.
    fn substitute(&self, value: &str, file: usize, line: u32) -> Result<String> {
        if !value.contains('$') {
            return Ok(value.to_string());
        }
        let mut order: Vec<&(String, String)> = self.params.iter().collect();
        order.sort_by_key(|(k, _)| std::cmp::Reverse(k.len()));
        let mut out = String::with_capacity(value.len());
        let bytes = value.as_bytes();
        let mut i = 0;
        while i < value.len() {
            if bytes[i] == b'\\' && value[i + 1..].starts_with('$') {
                out.push('$');
                i += 2;
                continue;
            }
            if bytes[i] == b'$' {
                let rest = &value[i + 1..];
                if let Some((k, v)) = order.iter().find(|(k, _)| rest.starts_with(k.as_str())) {
                    out.push_str(v);
                    i += 1 + k.len();
                    continue;
                }
                let name: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                return Err(self.fail(
                    file,
                    line,
                    format!("undefined parameter ${name} (no <default name=\"{name}\">)"),
                ));
            }
            let c = value[i..].chars().next().expect("in range");
            out.push(c);
            i += c.len_utf8();
        }
        Ok(out)
    }

    /// The element `node` with its subtree; `None` for `<default>` (recorded) — an `<include>`
    /// comes back as a `<scene>` whose children the caller splices in.
    fn convert(
        &mut self,
        doc: &roxmltree::Document,
        node: roxmltree::Node,
        file: usize,
        upgrade: bool,
    ) -> Result<Option<Elem>> {
        let line = doc.text_pos_at(node.range().start).row;
        let tag = node.tag_name().name().to_string();
        if node.ancestors().count() > MAX_NESTING {
            return Err(self.fail(
                file,
                line,
                format!("<{tag}>: elements nest deeper than {MAX_NESTING}"),
            ));
        }
        let mut attrs = Vec::new();
        for a in node.attributes() {
            let mut v = self.substitute(a.value(), file, line)?;
            // Mitsuba upgrades the names of properties; a `<default>`'s name is a parameter's
            // and stays as written (`$photonCount` finds `<default name="photonCount">`).
            if upgrade && a.name() == "name" && node.tag_name().name() != "default" {
                v = camel_to_snake(&v);
            }
            attrs.push((a.name().to_string(), v));
        }
        let mut elem = Elem {
            tag,
            attrs,
            children: Vec::new(),
            file,
            line,
        };
        match elem.tag.as_str() {
            "default" => {
                let (Some(name), Some(value)) = (elem.attr("name"), elem.attr("value")) else {
                    return Err(self.fail(file, line, "<default> needs name and value"));
                };
                if name.is_empty() {
                    return Err(self.fail(file, line, "<default>: the name is empty"));
                }
                if !self.params.iter().any(|(k, _)| k == name) {
                    self.params.push((name.to_string(), value.to_string()));
                }
                return Ok(None);
            }
            "include" => {
                let Some(name) = elem.attr("filename") else {
                    return Err(self.fail(file, line, "<include> needs a filename"));
                };
                let dir = self.files[file]
                    .parent()
                    .unwrap_or(Path::new("."))
                    .to_path_buf();
                let inc = self.parse_file(&dir.join(name), Some((file, line)))?;
                return Ok(Some(if inc.tag == "scene" {
                    inc
                } else {
                    Elem {
                        tag: "scene".into(),
                        attrs: Vec::new(),
                        children: vec![inc],
                        file,
                        line,
                    }
                }));
            }
            _ => {}
        }
        for child in node.children().filter(|n| n.is_element()) {
            if let Some(c) = self.convert(doc, child, file, upgrade)? {
                let included = child.tag_name().name() == "include";
                if included {
                    elem.children.extend(c.children);
                } else {
                    elem.children.push(c);
                }
            }
        }
        if upgrade && elem.tag == "bsdf" && elem.attr("type") == Some("diffuse") {
            for c in &mut elem.children {
                for (k, v) in &mut c.attrs {
                    if k == "name" && v == "diffuse_reflectance" {
                        *v = "reflectance".into();
                    }
                }
            }
        }
        Ok(Some(elem))
    }
}

/// A property's value.
#[derive(Clone, Debug)]
enum Value<'a> {
    Float(f64),
    Integer(i64),
    Boolean(bool),
    String(String),
    Rgb([f64; 3]),
    Vector([f64; 3]),
    Transform(Affine),
    Object(&'a Elem),
}

impl Value<'_> {
    fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "a float",
            Value::Integer(_) => "an integer",
            Value::Boolean(_) => "a boolean",
            Value::String(_) => "a string",
            Value::Rgb(_) => "a colour",
            Value::Vector(_) => "a point or vector",
            Value::Transform(_) => "a transform",
            Value::Object(_) => "an object",
        }
    }
}

struct Prop<'a> {
    name: String,
    value: Value<'a>,
    elem: &'a Elem,
    used: Cell<bool>,
}

/// The properties of one object element, each to be read exactly once.
struct Props<'a> {
    owner: &'a Elem,
    items: Vec<Prop<'a>>,
}

/// The second pass: objects translated into the scene.
struct Importer<'a> {
    parser: &'a Parser,
    ids: BTreeMap<String, &'a Elem>,
    scene: Scene,
    warnings: RefCell<Vec<String>>,
    /// Material name by the address of its BSDF element.
    materials: BTreeMap<usize, String>,
    /// The material of shapes without a BSDF, once made.
    default_bsdf: Option<String>,
    /// Textures made so far, and their names by the address of their element.
    textures: RefCell<BTreeMap<String, TextureDesc>>,
    texture_names: RefCell<BTreeMap<usize, String>>,
    /// How deep [`Importer::bsdf`] is in nested BSDFs.
    bsdf_depth: Cell<usize>,
    /// Directories `<path>` adds to the file search.
    search: Vec<PathBuf>,
}

fn parse_floats(s: &str) -> Option<Vec<f64>> {
    s.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
        .map(|t| t.parse::<f64>().ok())
        .collect()
}

impl<'a> Importer<'a> {
    fn file(&self, e: &Elem) -> &Path {
        &self.parser.files[e.file]
    }

    fn fail(&self, e: &Elem, msg: impl Into<String>) -> Error {
        Error::at(self.file(e), describe(e), msg)
    }

    fn warn(&self, e: &Elem, msg: impl AsRef<str>) {
        let w = format!(
            "{}: {}: {}",
            self.file(e).display(),
            describe(e),
            msg.as_ref()
        );
        self.warnings.borrow_mut().push(w);
    }

    fn vec3_attr(&self, e: &'a Elem, s: &str) -> Result<[f64; 3]> {
        match parse_floats(s).as_deref() {
            Some(&[x, y, z]) => self.finite3(e, [x, y, z]),
            _ => Err(self.fail(e, format!("\"{s}\" is not three numbers"))),
        }
    }

    fn finite3(&self, e: &Elem, v: [f64; 3]) -> Result<[f64; 3]> {
        if v.iter().all(|x| x.is_finite()) {
            Ok(v)
        } else {
            Err(self.fail(e, format!("{v:?} is not finite")))
        }
    }

    /// x, y, z attributes (or `value` with one or three numbers), missing ones `default`.
    fn xyz(&self, e: &'a Elem, default: f64) -> Result<[f64; 3]> {
        if let Some(v) = e.attr("value") {
            return match parse_floats(v).as_deref() {
                Some(&[a]) => self.finite3(e, [a; 3]),
                Some(&[a, b, c]) => self.finite3(e, [a, b, c]),
                _ => Err(self.fail(e, format!("value \"{v}\" must be one or three numbers"))),
            };
        }
        let mut out = [default; 3];
        for (i, k) in ["x", "y", "z"].iter().enumerate() {
            if let Some(s) = e.attr(k) {
                out[i] = s
                    .trim()
                    .parse()
                    .map_err(|_| self.fail(e, format!("{k}=\"{s}\" is not a number")))?;
            }
        }
        self.finite3(e, out)
    }

    fn transform(&self, e: &'a Elem) -> Result<Affine> {
        let mut t = Affine::IDENTITY;
        for op in &e.children {
            let step = match op.tag.as_str() {
                "translate" => Affine::translate(Vec3::from(self.xyz(op, 0.0)?)),
                "scale" => Affine::scale(Vec3::from(self.xyz(op, 1.0)?)),
                "rotate" => {
                    let axis = Vec3::from(self.xyz(op, 0.0)?);
                    let angle: f64 = op
                        .attr("angle")
                        .and_then(|a| a.trim().parse().ok())
                        .filter(|a: &f64| a.is_finite())
                        .ok_or_else(|| self.fail(op, "needs a finite angle (degrees)"))?;
                    let a = axis
                        .try_normalize()
                        .ok_or_else(|| self.fail(op, "the rotation axis is zero"))?;
                    rotation(a, angle)
                }
                "lookat" => {
                    let (Some(o), Some(tg)) = (op.attr("origin"), op.attr("target")) else {
                        return Err(self.fail(op, "needs origin and target"));
                    };
                    let origin = Vec3::from(self.vec3_attr(op, o)?);
                    let target = Vec3::from(self.vec3_attr(op, tg)?);
                    let dir = (target - origin)
                        .try_normalize()
                        .ok_or_else(|| self.fail(op, "origin and target coincide"))?;
                    let up = match op.attr("up") {
                        Some(u) => Vec3::from(self.vec3_attr(op, u)?),
                        None => Vec3::ZERO,
                    };
                    let up = if up == Vec3::ZERO {
                        dir.orthonormal_basis().0
                    } else {
                        up
                    };
                    let left = up
                        .cross(dir)
                        .try_normalize()
                        .ok_or_else(|| self.fail(op, "up is parallel to the viewing direction"))?;
                    let new_up = dir.cross(left);
                    Affine {
                        m: [
                            [left.x, new_up.x, dir.x],
                            [left.y, new_up.y, dir.y],
                            [left.z, new_up.z, dir.z],
                        ],
                        t: origin,
                    }
                }
                "matrix" => {
                    let v = op.attr("value").unwrap_or("");
                    let values = parse_floats(v).ok_or_else(|| {
                        self.fail(op, format!("value \"{v}\" is not a list of numbers"))
                    })?;
                    if let Some(x) = values.iter().find(|x| !x.is_finite()) {
                        return Err(self.fail(op, format!("an element is {x}: not finite")));
                    }
                    match values.len() {
                        16 => {
                            if values[12..] != [0.0, 0.0, 0.0, 1.0] {
                                return Err(self.fail(
                                    op,
                                    "the last row is not 0 0 0 1 (a projective matrix; only \
                                     affine transforms are supported)",
                                ));
                            }
                            let r =
                                |i: usize| [values[i], values[i + 1], values[i + 2], values[i + 3]];
                            Affine::from_rows4([r(0), r(4), r(8), r(12)])
                        }
                        9 => Affine {
                            m: [
                                [values[0], values[1], values[2]],
                                [values[3], values[4], values[5]],
                                [values[6], values[7], values[8]],
                            ],
                            t: Vec3::ZERO,
                        },
                        n => return Err(self.fail(op, format!("{n} values; a matrix has 9 or 16"))),
                    }
                }
                _ => {
                    return Err(self.fail(
                        op,
                        "unexpected element inside <transform> (translate, rotate, scale, \
                         lookat or matrix)",
                    ))
                }
            };
            t = step.compose(&t);
        }
        if !(t.m.iter().flatten().all(|v| v.is_finite()) && t.t.is_finite()) {
            return Err(self.fail(e, "the composed transform is not finite"));
        }
        Ok(t)
    }

    /// The properties and nested objects of an object element.
    fn props(&self, e: &'a Elem) -> Result<Props<'a>> {
        let mut items = Vec::new();
        let mut arg = 0;
        for c in &e.children {
            let name = match c.attr("name") {
                Some(n) => n.to_string(),
                None => {
                    arg += 1;
                    format!("_arg_{arg}")
                }
            };
            let value = match c.tag.as_str() {
                "float" => {
                    let v = c
                        .attr("value")
                        .ok_or_else(|| self.fail(c, "needs a value attribute"))?;
                    let x: f64 = v
                        .trim()
                        .parse()
                        .map_err(|_| self.fail(c, format!("\"{v}\" is not a number")))?;
                    if !x.is_finite() {
                        return Err(self.fail(c, format!("{x} is not finite")));
                    }
                    Value::Float(x)
                }
                "integer" => {
                    let v = c
                        .attr("value")
                        .ok_or_else(|| self.fail(c, "needs a value attribute"))?;
                    Value::Integer(
                        v.trim()
                            .parse()
                            .map_err(|_| self.fail(c, format!("\"{v}\" is not an integer")))?,
                    )
                }
                "boolean" => {
                    let v = c
                        .attr("value")
                        .ok_or_else(|| self.fail(c, "needs a value attribute"))?;
                    Value::Boolean(match v.to_ascii_lowercase().as_str() {
                        "true" => true,
                        "false" => false,
                        _ => return Err(self.fail(c, format!("\"{v}\" is not true or false"))),
                    })
                }
                "string" => Value::String(
                    c.attr("value")
                        .ok_or_else(|| self.fail(c, "needs a value attribute"))?
                        .to_string(),
                ),
                "rgb" => {
                    let v = c
                        .attr("value")
                        .ok_or_else(|| self.fail(c, "needs a value attribute"))?;
                    match parse_floats(v).as_deref() {
                        Some(&[a]) => Value::Rgb(self.finite3(c, [a; 3])?),
                        Some(&[a, b, d]) => Value::Rgb(self.finite3(c, [a, b, d])?),
                        _ => return Err(self.fail(c, "an rgb value is one or three numbers")),
                    }
                }
                "spectrum" => {
                    if c.attr("type").is_some() {
                        return Err(self.fail(c, "spectrum plugins are not supported"));
                    }
                    if c.attr("filename").is_some() {
                        return Err(self.fail(
                            c,
                            "spectral data files are not supported (luxest is RGB; give an \
                             <rgb> value)",
                        ));
                    }
                    let v = c
                        .attr("value")
                        .ok_or_else(|| self.fail(c, "needs a value attribute"))?;
                    match parse_floats(v).as_deref() {
                        Some(&[a]) if a.is_finite() => Value::Rgb([a; 3]),
                        _ => {
                            return Err(self.fail(
                                c,
                                format!(
                                    "spectrum \"{v}\": only a constant value is supported \
                                     (luxest is RGB; give an <rgb> value)"
                                ),
                            ))
                        }
                    }
                }
                "point" | "vector" => Value::Vector(self.xyz(c, 0.0)?),
                "transform" => Value::Transform(self.transform(c)?),
                "ref" => {
                    let id = c
                        .attr("id")
                        .ok_or_else(|| self.fail(c, "needs an id attribute"))?;
                    let target = self
                        .ids
                        .get(id)
                        .ok_or_else(|| self.fail(c, format!("no object has the id \"{id}\"")))?;
                    Value::Object(target)
                }
                "bsdf" | "shape" | "emitter" | "sensor" | "texture" | "film" | "rfilter"
                | "sampler" | "medium" | "phase" | "volume" | "integrator" => Value::Object(c),
                "alias" | "path" => continue,
                other => {
                    return Err(self.fail(c, format!("unknown element <{other}>")));
                }
            };
            items.push(Prop {
                name,
                value,
                elem: c,
                used: Cell::new(false),
            });
        }
        Ok(Props { owner: e, items })
    }

    /// Refuses the first property nothing read.
    fn check_done(&self, p: &Props) -> Result<()> {
        match p.items.iter().find(|i| !i.used.get()) {
            None => Ok(()),
            Some(i) => Err(self.fail(
                i.elem,
                format!(
                    "parameter \"{}\" of <{} type=\"{}\"> is not supported by the importer",
                    i.name,
                    p.owner.tag,
                    p.owner.attr("type").unwrap_or("")
                ),
            )),
        }
    }
}

/// The rotation part of `a` made exactly orthonormal (Gram-Schmidt on its columns), when its
/// columns are orthonormal within 1e-3 (Mitsuba's `has_scale` tolerance) and it does not mirror.
fn nearly_rotation(a: &Affine) -> Option<[[f64; 3]; 3]> {
    let m = &a.m;
    let col = |j: usize| Vec3::new(m[0][j], m[1][j], m[2][j]);
    let (x, y, z) = (col(0), col(1), col(2));
    let close = |v: f64, want: f64| (v - want).abs() <= 1e-3;
    let orthonormal = close(x.dot(x), 1.0)
        && close(y.dot(y), 1.0)
        && close(z.dot(z), 1.0)
        && close(x.dot(y), 0.0)
        && close(x.dot(z), 0.0)
        && close(y.dot(z), 0.0);
    if !orthonormal || a.determinant() <= 0.0 {
        return None;
    }
    let x = x.try_normalize()?;
    let y = (y - x * x.dot(y)).try_normalize()?;
    let z = x.cross(y);
    Some([[x.x, y.x, z.x], [x.y, y.y, z.y], [x.z, y.z, z.z]])
}

/// Rotation about the unit axis `a` by `deg` degrees (right-handed; Rodrigues' formula).
fn rotation(a: Vec3, deg: f64) -> Affine {
    let (s, c) = deg.to_radians().sin_cos();
    let t = 1.0 - c;
    Affine {
        m: [
            [
                t * a.x * a.x + c,
                t * a.x * a.y - s * a.z,
                t * a.x * a.z + s * a.y,
            ],
            [
                t * a.x * a.y + s * a.z,
                t * a.y * a.y + c,
                t * a.y * a.z - s * a.x,
            ],
            [
                t * a.x * a.z - s * a.y,
                t * a.y * a.z + s * a.x,
                t * a.z * a.z + c,
            ],
        ],
        t: Vec3::ZERO,
    }
}

impl<'a> Props<'a> {
    fn get(&self, name: &str) -> Option<&Prop<'a>> {
        let p = self.items.iter().find(|i| i.name == name)?;
        p.used.set(true);
        Some(p)
    }
}

/// A property reader bound to the importer for messages.
struct Reader<'i, 'a> {
    imp: &'i Importer<'a>,
    props: Props<'a>,
}

impl<'a> Reader<'_, 'a> {
    fn wrong(&self, p: &Prop, want: &str) -> Error {
        if let Value::Object(t) = p.value {
            if t.tag == "texture" {
                return self.imp.fail(
                    t,
                    format!(
                        "a texture for \"{}\" is not supported (luxest takes a constant here)",
                        p.name
                    ),
                );
            }
        }
        self.imp.fail(
            p.elem,
            format!(
                "parameter \"{}\" must be {want}, not {}",
                p.name,
                p.value.kind()
            ),
        )
    }
    fn float(&self, name: &str, default: f64) -> Result<f64> {
        match self.props.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Float(x) => Ok(x),
                Value::Integer(i) => Ok(i as f64),
                _ => Err(self.wrong(p, "a float")),
            },
        }
    }
    fn integer(&self, name: &str, default: i64) -> Result<i64> {
        match self.props.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Integer(i) => Ok(i),
                _ => Err(self.wrong(p, "an integer")),
            },
        }
    }
    fn boolean(&self, name: &str, default: bool) -> Result<bool> {
        match self.props.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(b) => Ok(b),
                _ => Err(self.wrong(p, "a boolean")),
            },
        }
    }
    fn string(&self, name: &str) -> Result<Option<String>> {
        match self.props.get(name) {
            None => Ok(None),
            Some(p) => match &p.value {
                Value::String(s) => Ok(Some(s.clone())),
                _ => Err(self.wrong(p, "a string")),
            },
        }
    }
    fn point(&self, name: &str, default: [f64; 3]) -> Result<Vec3> {
        match self.props.get(name) {
            None => Ok(Vec3::from(default)),
            Some(p) => match p.value {
                Value::Vector(v) => Ok(Vec3::from(v)),
                _ => Err(self.wrong(p, "a point")),
            },
        }
    }
    fn transform(&self, name: &str) -> Result<Affine> {
        match self.props.get(name) {
            None => Ok(Affine::IDENTITY),
            Some(p) => match p.value {
                Value::Transform(t) => Ok(t),
                _ => Err(self.wrong(p, "a transform")),
            },
        }
    }
    /// A colour parameter that may be a `bitmap` texture: (the constant, the texture's name);
    /// with a texture the constant is 1 (the texture multiplies it).
    fn color_or_texture(&self, name: &str, default: f64) -> Result<(Rgb, Option<String>)> {
        if let Some(p) = self.props.items.iter().find(|i| i.name == name) {
            if let Value::Object(e) = p.value {
                if e.tag == "texture" {
                    p.used.set(true);
                    return Ok((Rgb::WHITE, Some(self.imp.texture(e)?)));
                }
            }
        }
        Ok((self.color(name, default)?, None))
    }
    /// A float parameter that may be a `bitmap` texture, as [`Reader::color_or_texture`].
    fn float_or_texture(&self, name: &str, default: f64) -> Result<(f64, Option<String>)> {
        if let Some(p) = self.props.items.iter().find(|i| i.name == name) {
            if let Value::Object(e) = p.value {
                if e.tag == "texture" {
                    p.used.set(true);
                    return Ok((1.0, Some(self.imp.texture(e)?)));
                }
            }
        }
        Ok((self.float(name, default)?, None))
    }
    /// A colour parameter: `rgb`, constant `spectrum` or `float`; a texture is an error.
    fn color(&self, name: &str, default: f64) -> Result<Rgb> {
        match self.props.get(name) {
            None => Ok(Rgb::splat(default)),
            Some(p) => match &p.value {
                Value::Rgb(c) => Ok(Rgb(*c)),
                Value::Float(x) => Ok(Rgb::splat(*x)),
                _ => Err(self.wrong(p, "a colour (rgb, spectrum or float)")),
            },
        }
    }
    /// The nested objects of element kind `tag`, in order.
    fn objects(&self, tag: &str) -> Vec<&'a Elem> {
        self.props
            .items
            .iter()
            .filter_map(|p| match p.value {
                Value::Object(e) if e.tag == tag => {
                    p.used.set(true);
                    Some(e)
                }
                _ => None,
            })
            .collect()
    }
    fn done(self) -> Result<()> {
        self.imp.check_done(&self.props)
    }
}

/// The index of refraction of a Mitsuba `int_ior`/`ext_ior`: a number or a name of its table.
fn ior(r: &Reader, name: &str, default: &str) -> Result<f64> {
    let Some(p) = r.props.get(name) else {
        return Ok(named_ior(default).expect("a default of the table"));
    };
    match &p.value {
        Value::Float(x) => Ok(*x),
        Value::String(s) => named_ior(s).ok_or_else(|| {
            r.imp.fail(
                p.elem,
                format!(
                    "unknown index of refraction \"{s}\" (Mitsuba's names: {})",
                    super::mitsuba_tables::IOR
                        .iter()
                        .map(|(n, _)| *n)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        }),
        _ => Err(r.wrong(p, "a float or an IOR name")),
    }
}

fn named_ior(name: &str) -> Option<f64> {
    let lower = name.to_ascii_lowercase();
    super::mitsuba_tables::IOR
        .iter()
        .find(|(n, _)| *n == lower)
        .map(|(_, v)| *v)
}

/// A BSDF as translated: the material and whether Mitsuba shades it from both sides.
struct Bsdf {
    material: Material,
    two_sided: bool,
    /// Texture multiplying the main colour, the microfacet α; the `mask` opacity.
    color: Option<String>,
    roughness: Option<String>,
    opacity: Option<Opacity>,
    /// A `normalmap`'s texture.
    normal: Option<String>,
}

impl Bsdf {
    fn plain(material: Material, two_sided: bool) -> Bsdf {
        Bsdf {
            material,
            two_sided,
            color: None,
            roughness: None,
            opacity: None,
            normal: None,
        }
    }
    fn textured(&self) -> bool {
        self.color.is_some()
            || self.roughness.is_some()
            || self.opacity.is_some()
            || self.normal.is_some()
    }
}

impl<'a> Importer<'a> {
    fn reader(&self, e: &'a Elem) -> Result<Reader<'_, 'a>> {
        Ok(Reader {
            imp: self,
            props: self.props(e)?,
        })
    }

    /// The isotropic microfacet roughness of a rough BSDF (Mitsuba's default: Beckmann,
    /// α = 0.1).
    fn microfacet(&self, r: &Reader) -> Result<(Microfacet, Option<String>)> {
        let (name, alpha, texture) = self.microfacet_alpha(r)?;
        let distribution = match name.as_str() {
            "ggx" => MicrofacetDistribution::Ggx,
            "beckmann" => MicrofacetDistribution::Beckmann,
            other => {
                return Err(self.fail(
                    r.props.owner,
                    format!("unknown distribution \"{other}\" (beckmann or ggx)"),
                ))
            }
        };
        Ok((
            Microfacet {
                distribution,
                alpha,
            },
            texture,
        ))
    }

    fn microfacet_alpha(&self, r: &Reader) -> Result<(String, f64, Option<String>)> {
        let distribution = r
            .string("distribution")?
            .unwrap_or_else(|| "beckmann".into())
            .to_ascii_lowercase();
        if r.props
            .items
            .iter()
            .any(|i| i.name == "alpha_u" || i.name == "alpha_v")
        {
            let (u, v) = (r.float("alpha_u", -1.0)?, r.float("alpha_v", -1.0)?);
            if u != v {
                return Err(self.fail(
                    r.props.owner,
                    format!("anisotropic roughness (alpha_u {u}, alpha_v {v}) is not supported"),
                ));
            }
            r.boolean("sample_visible", true)?;
            return Ok((distribution, u, None));
        }
        let (alpha, texture) = r.float_or_texture("alpha", 0.1)?;
        r.boolean("sample_visible", true)?;
        Ok((distribution, alpha, texture))
    }

    fn bsdf(&self, e: &'a Elem) -> Result<Bsdf> {
        let depth = self.bsdf_depth.get();
        if depth >= MAX_NESTING {
            return Err(self.fail(
                e,
                format!("BSDFs nest deeper than {MAX_NESTING} (a <ref> to an enclosing BSDF?)"),
            ));
        }
        self.bsdf_depth.set(depth + 1);
        let b = self.bsdf_at(e);
        self.bsdf_depth.set(depth);
        b
    }

    fn bsdf_at(&self, e: &'a Elem) -> Result<Bsdf> {
        let plugin = e.attr("type").unwrap_or("");
        let r = self.reader(e)?;
        let color;
        let mut roughness_texture = None;
        let material = match plugin {
            "twosided" => {
                let inner = r.objects("bsdf");
                let b = match inner.as_slice() {
                    [one] => self.bsdf(one)?,
                    [_, _] => {
                        return Err(self.fail(
                            e,
                            "twosided with different front and back BSDFs is not supported",
                        ))
                    }
                    _ => return Err(self.fail(e, "twosided needs one nested BSDF")),
                };
                r.done()?;
                if b.normal.is_some() {
                    // Mitsuba's twosided mirrors the normal map's frame on the back side;
                    // luxest's two-sided normal-mapped surface is normalmap(twosided(…)), whose
                    // back side sees the mapped normal reversed.
                    return Err(self.fail(
                        e,
                        "twosided around a normalmap is not supported (put the normalmap \
                         outside: normalmap(twosided(…)))",
                    ));
                }
                return Ok(Bsdf {
                    two_sided: true,
                    ..b
                });
            }
            "normalmap" => {
                let texture = match r.props.get("normalmap") {
                    Some(p) => match &p.value {
                        Value::Object(t) if t.tag == "texture" => {
                            p.used.set(true);
                            self.texture(t)?
                        }
                        _ => return Err(r.wrong(p, "a texture")),
                    },
                    None => return Err(self.fail(e, "normalmap needs a normalmap texture")),
                };
                for flag in ["flip_invalid_normals", "use_shadowing_function"] {
                    if !r.boolean(flag, true)? {
                        return Err(self.fail(
                            e,
                            format!(
                                "{flag} false is not supported (luxest's normal maps are \
                                     Mitsuba's defaults)"
                            ),
                        ));
                    }
                }
                let inner = r.objects("bsdf");
                let [one] = inner.as_slice() else {
                    return Err(self.fail(e, "normalmap needs one nested BSDF"));
                };
                let b = self.bsdf(one)?;
                r.done()?;
                if b.normal.is_some() {
                    return Err(self.fail(e, "a normalmap inside a normalmap is not supported"));
                }
                return Ok(Bsdf {
                    normal: Some(texture),
                    ..b
                });
            }
            "mask" => {
                let (value, texture) = r.float_or_texture("opacity", 0.5)?;
                let inner = r.objects("bsdf");
                let [one] = inner.as_slice() else {
                    return Err(self.fail(e, "mask needs one nested BSDF"));
                };
                let b = self.bsdf(one)?;
                r.done()?;
                if b.opacity.is_some() {
                    return Err(self.fail(e, "a mask inside a mask is not supported"));
                }
                if !(0.0..=1.0).contains(&value) {
                    return Err(self.fail(e, format!("opacity {value} is outside [0, 1]")));
                }
                return Ok(Bsdf {
                    opacity: Some(Opacity {
                        texture,
                        // Mitsuba's bitmap drops an image's alpha: a mask reads its colour.
                        channel: OpacityChannel::Luminance,
                        value,
                        cutoff: None,
                    }),
                    ..b
                });
            }
            "diffuse" => {
                let (reflectance, t) = r.color_or_texture("reflectance", 0.5)?;
                color = t;
                Material::Lambertian { reflectance }
            }
            "dielectric" => {
                let int = ior(&r, "int_ior", "bk7")?;
                let ext = ior(&r, "ext_ior", "air")?;
                for k in ["specular_reflectance", "specular_transmittance"] {
                    if r.color(k, 1.0)? != Rgb::WHITE {
                        return Err(self.fail(e, format!("{k} other than 1 is not supported")));
                    }
                }
                r.done()?;
                // A dielectric refracts from both sides: it is two-sided by nature.
                return Ok(Bsdf::plain(Material::Dielectric { ior: int / ext }, true));
            }
            "conductor" | "roughconductor" => {
                let material = r.string("material")?.unwrap_or_else(|| "none".into());
                let explicit = r
                    .props
                    .items
                    .iter()
                    .any(|i| i.name == "eta" || i.name == "k");
                let (eta, k) = if explicit || material == "none" {
                    if material != "none" {
                        return Err(self.fail(e, "give either eta and k or a material, not both"));
                    }
                    (r.color("eta", 0.0)?, r.color("k", 1.0)?)
                } else {
                    let (_, eta, k) = super::mitsuba_tables::CONDUCTORS
                        .iter()
                        .find(|(n, _, _)| *n == material)
                        .ok_or_else(|| {
                            self.fail(
                                e,
                                format!(
                                    "unknown conductor material \"{material}\" (Mitsuba's: {})",
                                    super::mitsuba_tables::CONDUCTORS
                                        .iter()
                                        .map(|(n, _, _)| *n)
                                        .collect::<Vec<_>>()
                                        .join(", ")
                                ),
                            )
                        })?;
                    (Rgb(*eta), Rgb(*k))
                };
                let (specular_reflectance, t) = r.color_or_texture("specular_reflectance", 1.0)?;
                color = t;
                let perfect = eta == Rgb::splat(0.0) && k == Rgb::WHITE;
                if plugin == "conductor" && perfect {
                    // eta 0, k 1: Fresnel reflectance 1 at every angle, an ideal mirror.
                    Material::Mirror {
                        reflectance: specular_reflectance,
                    }
                } else {
                    let roughness = if plugin == "roughconductor" {
                        let (m, t) = self.microfacet(&r)?;
                        roughness_texture = t;
                        Some(m)
                    } else {
                        None
                    };
                    Material::Conductor {
                        eta,
                        k,
                        specular_reflectance,
                        roughness,
                    }
                }
            }
            "plastic" | "roughplastic" => {
                let int = ior(&r, "int_ior", "polypropylene")?;
                let ext = ior(&r, "ext_ior", "air")?;
                let roughness = if plugin == "roughplastic" {
                    let (m, t) = self.microfacet(&r)?;
                    roughness_texture = t;
                    Some(m)
                } else {
                    None
                };
                let (diffuse_reflectance, t) = r.color_or_texture("diffuse_reflectance", 0.5)?;
                color = t;
                Material::Plastic {
                    diffuse_reflectance,
                    specular_reflectance: r.color("specular_reflectance", 1.0)?,
                    ior: int / ext,
                    nonlinear: r.boolean("nonlinear", false)?,
                    roughness,
                }
            }
            "thindielectric" | "roughdielectric" => {
                let int = ior(&r, "int_ior", "bk7")?;
                let ext = ior(&r, "ext_ior", "air")?;
                for k in ["specular_reflectance", "specular_transmittance"] {
                    if r.color(k, 1.0)? != Rgb::WHITE {
                        return Err(self.fail(e, format!("{k} other than 1 is not supported")));
                    }
                }
                let mut b = if plugin == "thindielectric" {
                    Bsdf::plain(Material::ThinDielectric { ior: int / ext }, true)
                } else {
                    let (m, t) = self.microfacet(&r)?;
                    Bsdf {
                        roughness: t,
                        ..Bsdf::plain(
                            Material::RoughDielectric {
                                ior: int / ext,
                                roughness: m,
                            },
                            true,
                        )
                    }
                };
                r.done()?;
                // Transmitting BSDFs scatter from both sides by nature.
                b.two_sided = true;
                return Ok(b);
            }
            "blendbsdf" => {
                let weight = match r.props.get("weight") {
                    None => return Err(self.fail(e, "needs a weight")),
                    Some(p) => match &p.value {
                        Value::Float(w) => *w,
                        Value::Object(t) if t.tag == "texture" => {
                            return Err(self.fail(
                                t,
                                "a textured blend weight is not supported (luxest's Blend has \
                                 a constant weight)",
                            ))
                        }
                        _ => return Err(r.wrong(p, "a float")),
                    },
                };
                let inner = r.objects("bsdf");
                let [first, second] = inner.as_slice() else {
                    return Err(self.fail(e, "blendbsdf needs two nested BSDFs"));
                };
                let (a, b) = (self.bsdf(first)?, self.bsdf(second)?);
                if a.two_sided != b.two_sided {
                    return Err(self.fail(
                        e,
                        "blendbsdf of a one-sided and a two-sided BSDF is not supported",
                    ));
                }
                if a.textured() || b.textured() {
                    return Err(self.fail(
                        e,
                        "textured or masked BSDFs inside a blendbsdf are not supported (a \
                         texture would apply to both)",
                    ));
                }
                r.done()?;
                return Ok(Bsdf::plain(
                    Material::Blend {
                        weight,
                        first: Box::new(a.material),
                        second: Box::new(b.material),
                    },
                    a.two_sided,
                ));
            }
            other => return Err(self.fail(e, format!("unsupported BSDF \"{other}\""))),
        };
        r.done()?;
        Ok(Bsdf {
            color,
            roughness: roughness_texture,
            ..Bsdf::plain(material, false)
        })
    }

    /// Registers a translated BSDF as a material (and its surface, when it has textures, a
    /// mask or one side); returns the material's name.
    fn register(&mut self, b: Bsdf, wanted: String) -> String {
        let mut name = wanted;
        while self.scene.materials.contains_key(&name) {
            name.push('\'');
        }
        if b.textured() || !b.two_sided {
            self.scene.surfaces.insert(
                name.clone(),
                Surface {
                    color: b.color,
                    roughness: b.roughness,
                    opacity: b.opacity,
                    normal: b.normal,
                    normal_scale: [1.0, 1.0],
                    two_sided: b.two_sided,
                },
            );
        }
        self.scene.materials.insert(name.clone(), b.material);
        name
    }

    /// The texture of a `<texture>` element (a `bitmap`), registered on first use; its name.
    fn texture(&self, e: &'a Elem) -> Result<String> {
        let key = e as *const Elem as usize;
        if let Some(n) = self.texture_names.borrow().get(&key) {
            return Ok(n.clone());
        }
        let plugin = e.attr("type").unwrap_or("");
        if plugin != "bitmap" && plugin != "checkerboard" {
            return Err(self.fail(
                e,
                format!("unsupported texture \"{plugin}\" (bitmap and checkerboard are)"),
            ));
        }
        let r = self.reader(e)?;
        let checker = plugin == "checkerboard";
        let (file, path, checkerboard) = if checker {
            // Mitsuba's defaults: color0 0.4, color1 0.2.
            let colors = [r.color("color0", 0.4)?, r.color("color1", 0.2)?];
            ("checkerboard".to_string(), String::new(), Some(colors))
        } else {
            let file = r
                .string("filename")?
                .ok_or_else(|| self.fail(e, "needs a filename (bitmap data is not supported)"))?;
            let path = self.resolve_file(e, &file)?;
            (file, path, None)
        };
        let raw = !checker && r.boolean("raw", false)?;
        // A checkerboard has neither (its nearest 2 × 2 texels repeat).
        let (wrap, filter) = if checker {
            (Wrap::Repeat, Filter::Nearest)
        } else {
            let wrap = match r.string("wrap_mode")?.as_deref().unwrap_or("repeat") {
                "repeat" => Wrap::Repeat,
                "mirror" => Wrap::Mirror,
                "clamp" => Wrap::Clamp,
                other => return Err(self.fail(e, format!("unknown wrap_mode \"{other}\""))),
            };
            let filter = match r.string("filter_type")?.as_deref().unwrap_or("bilinear") {
                "bilinear" => Filter::Bilinear,
                "nearest" => Filter::Nearest,
                other => return Err(self.fail(e, format!("unknown filter_type \"{other}\""))),
            };
            (wrap, filter)
        };
        let mut to_uv = r.transform("to_uv")?;
        // Mitsuba's upgrade of version < 2 files: uoffset, voffset, uscale, vscale become
        // to_uv = scale · translate.
        if self.parser.legacy.get(e.file).copied().unwrap_or(false) {
            let old = ["uoffset", "voffset", "uscale", "vscale"];
            if old
                .iter()
                .any(|k| r.props.items.iter().any(|i| i.name == *k))
            {
                if to_uv != Affine::IDENTITY {
                    return Err(self.fail(e, "give either to_uv or uoffset/uscale, not both"));
                }
                let offset = Vec3::new(r.float("uoffset", 0.0)?, r.float("voffset", 0.0)?, 0.0);
                let scale = Vec3::new(r.float("uscale", 1.0)?, r.float("vscale", 1.0)?, 1.0);
                to_uv = Affine::scale(scale).compose(&Affine::translate(offset));
            }
        }
        if !checker {
            r.boolean("accel", true)?;
            if let Some(f) = r.string("format")? {
                if f != "auto" {
                    return Err(self.fail(e, format!("format \"{f}\" is not supported")));
                }
            }
        }
        r.done()?;
        let m = &to_uv.m;
        if m[0][2] != 0.0 || m[1][2] != 0.0 {
            return Err(self.fail(e, "to_uv mixes in a third coordinate (a 2D transform only)"));
        }
        let uv_transform = (to_uv != Affine::IDENTITY).then_some(UvTransform([
            [m[0][0], m[0][1], to_uv.t.x],
            [m[1][0], m[1][1], to_uv.t.y],
        ]));
        let stem = self
            .file(e)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut name = match e.attr("id") {
            Some(id) => id.to_string(),
            None => format!("{file}@{stem}:{}", e.line),
        };
        let mut textures = self.textures.borrow_mut();
        while textures.contains_key(&name) {
            name.push('\'');
        }
        textures.insert(
            name.clone(),
            TextureDesc {
                path,
                checkerboard,
                // raw: the stored values as they are; otherwise the file's own encoding.
                encoding: raw.then_some(Encoding::Linear),
                wrap,
                filter,
                uv_transform,
            },
        );
        self.texture_names.borrow_mut().insert(key, name.clone());
        Ok(name)
    }

    /// The name of the material of a BSDF element, translating it on first use.
    fn material(&mut self, e: &'a Elem) -> Result<String> {
        let key = e as *const Elem as usize;
        if let Some(n) = self.materials.get(&key) {
            return Ok(n.clone());
        }
        let b = self.bsdf(e)?;
        let stem = self
            .file(e)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let wanted = match e.attr("id") {
            Some(id) => id.to_string(),
            None => format!("{}@{stem}:{}", e.attr("type").unwrap_or("bsdf"), e.line),
        };
        let name = self.register(b, wanted);
        self.materials.insert(key, name.clone());
        Ok(name)
    }

    /// Mitsuba's BSDF of a shape that has none: a one-sided diffuse of reflectance 0.5.
    fn default_material(&mut self) -> String {
        if let Some(n) = &self.default_bsdf {
            return n.clone();
        }
        let b = Bsdf::plain(
            Material::Lambertian {
                reflectance: Rgb::splat(0.5),
            },
            false,
        );
        let name = self.register(b, "diffuse (Mitsuba's default)".to_string());
        self.default_bsdf = Some(name.clone());
        name
    }

    fn resolve_file(&self, e: &Elem, name: &str) -> Result<String> {
        let here = self
            .file(e)
            .parent()
            .unwrap_or(Path::new("."))
            .to_path_buf();
        let main = self.parser.files[0]
            .parent()
            .unwrap_or(Path::new("."))
            .to_path_buf();
        let candidates = std::iter::once(here)
            .chain(std::iter::once(main))
            .chain(self.search.iter().cloned());
        for dir in candidates {
            let full = dir.join(name);
            if full.is_file() {
                return Ok(scene_relative(&full, &self.parser.files[0]));
            }
        }
        Err(self.fail(e, format!("file \"{name}\" not found")))
    }

    fn shape(&mut self, e: &'a Elem) -> Result<()> {
        let plugin = e.attr("type").unwrap_or("");
        let r = self.reader(e)?;
        let mut to_world = r.transform("to_world")?;
        let flip_normals = r.boolean("flip_normals", false)?;
        let shape = match plugin {
            "obj" | "ply" => {
                let file = r
                    .string("filename")?
                    .ok_or_else(|| self.fail(e, "needs a filename"))?;
                let path = self.resolve_file(e, &file)?;
                let flip_tex = r.boolean("flip_tex_coords", plugin == "obj")?;
                if flip_tex != (plugin == "obj") {
                    return Err(self.fail(
                        e,
                        format!("flip_tex_coords = {flip_tex} is not supported for {plugin}"),
                    ));
                }
                if plugin == "obj" {
                    Shape::Obj { path, usemtl: None }
                } else {
                    Shape::Ply { path }
                }
            }
            "serialized" => {
                let file = r
                    .string("filename")?
                    .ok_or_else(|| self.fail(e, "needs a filename"))?;
                let path = self.resolve_file(e, &file)?;
                let shape_index = r.integer("shape_index", 0)?;
                let shape_index = u32::try_from(shape_index)
                    .map_err(|_| self.fail(e, format!("shape_index {shape_index} is negative")))?;
                Shape::Serialized { path, shape_index }
            }
            "rectangle" => Shape::Quad {
                corner: Vec3::new(-1.0, -1.0, 0.0),
                u: Vec3::new(2.0, 0.0, 0.0),
                v: Vec3::new(0.0, 2.0, 0.0),
            },
            "cube" => Shape::Box {
                size: Vec3::splat(2.0),
            },
            "sphere" => {
                let center = r.point("center", [0.0; 3])?;
                let radius = r.float("radius", 1.0)?;
                to_world = to_world.compose(&Affine::translate(center));
                Shape::Sphere {
                    radius,
                    subdivisions: SPHERE_SUBDIVISIONS,
                }
            }
            "disk" => {
                // The regular polygon with the unit disk's area: r² · (n/2) sin(2π/n) = π.
                let n = DISK_SEGMENTS as f64;
                let tau = std::f64::consts::TAU;
                let radius = (tau / (n * (tau / n).sin())).sqrt();
                Shape::Polygon {
                    vertices: (0..DISK_SEGMENTS)
                        .map(|k| {
                            let phi = tau * k as f64 / n;
                            Vec3::new(radius * phi.cos(), radius * phi.sin(), 0.0)
                        })
                        .collect(),
                }
            }
            other => return Err(self.fail(e, format!("unsupported shape \"{other}\""))),
        };
        let face_normals = r.boolean("face_normals", false)?;
        // Mitsuba computes vertex normals for the mesh files that have none.
        let mesh_file = matches!(
            shape,
            Shape::Obj { .. } | Shape::Ply { .. } | Shape::Serialized { .. }
        );
        let bsdfs = r.objects("bsdf");
        let emitters = r.objects("emitter");
        let material = match bsdfs.as_slice() {
            [] => None,
            [b] => Some(*b),
            _ => return Err(self.fail(e, "more than one BSDF")),
        };
        let emission = match emitters.as_slice() {
            [] => None,
            [em] => Some(self.area_emitter(em)?),
            _ => return Err(self.fail(e, "more than one emitter")),
        };
        r.done()?;
        let material = match material {
            Some(b) => self.material(b)?,
            None => self.default_material(),
        };
        let m = to_world;
        let matrix = [
            [m.m[0][0], m.m[0][1], m.m[0][2], m.t.x],
            [m.m[1][0], m.m[1][1], m.m[1][2], m.t.y],
            [m.m[2][0], m.m[2][1], m.m[2][2], m.t.z],
        ];
        let transform = Transform {
            matrix: (m != Affine::IDENTITY).then_some(matrix),
            ..Transform::default()
        };
        if m.determinant() == 0.0 {
            return Err(self.fail(e, "to_world is singular (flattens the shape)"));
        }
        let name = e.attr("id").map(str::to_string);
        self.scene.objects.push(Object {
            name,
            shape,
            transform,
            material,
            emission,
            flip_normals,
            face_normals,
            compute_normals: mesh_file,
        });
        Ok(())
    }

    fn area_emitter(&self, e: &'a Elem) -> Result<Emission> {
        let plugin = e.attr("type").unwrap_or("");
        if plugin != "area" {
            return Err(self.fail(
                e,
                format!("a {plugin} emitter inside a shape (only area emitters are)"),
            ));
        }
        let r = self.reader(e)?;
        let (radiance, texture) = r.color_or_texture("radiance", 1.0)?;
        r.done()?;
        Ok(match texture {
            Some(texture) => Emission::Texture {
                texture,
                scale: Rgb::WHITE,
            },
            None => Emission::Radiance(radiance),
        })
    }

    fn emitter(&mut self, e: &'a Elem) -> Result<()> {
        let plugin = e.attr("type").unwrap_or("");
        let r = self.reader(e)?;
        match plugin {
            "point" => {
                let to_world = r.transform("to_world")?;
                let position = to_world.apply_point(r.point("position", [0.0; 3])?);
                let intensity = r.color("intensity", 1.0)?;
                r.done()?;
                let y = intensity.luminance();
                if y.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                    || intensity.min_component() < 0.0
                {
                    return Err(self.fail(
                        e,
                        "the intensity must be non-negative with positive luminance",
                    ));
                }
                self.scene.point_lights.push(PointLight {
                    name: e.attr("id").map(str::to_string),
                    position,
                    power: PointPower::Intensity(y),
                    color: intensity,
                    spot: None,
                });
                Ok(())
            }
            "spot" => {
                let to_world = r.transform("to_world")?;
                let intensity = r.color("intensity", 1.0)?;
                if r.props.items.iter().any(|i| i.name == "texture") {
                    return Err(
                        self.fail(e, "a projected texture on a spot light is not supported")
                    );
                }
                let cutoff_deg = r.float("cutoff_angle", 20.0)?;
                let beam_width_deg = r.float("beam_width", cutoff_deg * 3.0 / 4.0)?;
                r.done()?;
                let y = intensity.luminance();
                if y.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                    || intensity.min_component() < 0.0
                {
                    return Err(self.fail(
                        e,
                        "the intensity must be non-negative with positive luminance",
                    ));
                }
                self.scene.point_lights.push(PointLight {
                    name: e.attr("id").map(str::to_string),
                    position: to_world.apply_point(Vec3::ZERO),
                    power: PointPower::Intensity(y),
                    color: intensity,
                    spot: Some(Spot {
                        direction: to_world.apply_vector(Vec3::new(0.0, 0.0, 1.0)),
                        cutoff_deg,
                        beam_width_deg,
                    }),
                });
                Ok(())
            }
            "constant" | "envmap" => {
                if self.scene.environment.is_some() {
                    return Err(self.fail(e, "a second environment emitter (luxest has one)"));
                }
                let env = if plugin == "constant" {
                    let radiance = r.color("radiance", 1.0)?;
                    r.done()?;
                    Environment::Constant(radiance)
                } else {
                    let file = r
                        .string("filename")?
                        .ok_or_else(|| self.fail(e, "needs a filename"))?;
                    if !file.to_ascii_lowercase().ends_with(".exr") {
                        return Err(self.fail(
                            e,
                            format!("environment map \"{file}\": only OpenEXR maps are supported"),
                        ));
                    }
                    let path = self.resolve_file(e, &file)?;
                    let scale = r.float("scale", 1.0)?;
                    let to_world = r.transform("to_world")?;
                    r.done()?;
                    // Directions ignore the translation; a rotation written with few digits is
                    // made exactly orthonormal (Mitsuba's own tolerance for scale is 1e-3).
                    let Some(rotation) = nearly_rotation(&to_world) else {
                        return Err(self.fail(
                            e,
                            "the environment map's to_world must be a rotation (no scale, \
                             shear or mirror)",
                        ));
                    };
                    Environment::Map {
                        path,
                        scale,
                        to_world: rotation,
                    }
                };
                self.scene.environment = Some(env);
                Ok(())
            }
            "area" => Err(self.fail(e, "an area emitter must be inside a shape")),
            other => Err(self.fail(e, format!("unsupported emitter \"{other}\""))),
        }
    }

    fn sensor(&mut self, e: &'a Elem) -> Result<()> {
        let plugin = e.attr("type").unwrap_or("");
        if plugin != "perspective" {
            return Err(self.fail(
                e,
                format!(
                    "unsupported sensor \"{plugin}\" (luxest's camera is a pinhole: perspective)"
                ),
            ));
        }
        let r = self.reader(e)?;
        let films = r.objects("film");
        let (width, height) = match films.as_slice() {
            [] => (768, 576),
            [f] => self.film(f)?,
            _ => return Err(self.fail(e, "more than one film")),
        };
        for s in r.objects("sampler") {
            self.warn(
                s,
                "ignored: luxest's sample count is given on its command line",
            );
        }
        let aspect = width as f64 / height as f64;
        let has_fov = r.props.items.iter().any(|i| i.name == "fov");
        let has_focal = r.props.items.iter().any(|i| i.name == "focal_length");
        if has_fov && has_focal {
            return Err(self.fail(e, "give fov or focal_length, not both"));
        }
        let (fov, axis) = if has_focal {
            let f = r.string("focal_length")?.unwrap_or_default();
            let mm: f64 = f
                .trim_end_matches("mm")
                .trim()
                .parse()
                .ok()
                .filter(|v: &f64| *v > 0.0)
                .ok_or_else(|| self.fail(e, format!("focal_length \"{f}\" is not <x>mm")))?;
            (
                2.0 * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * mm))
                    .atan()
                    .to_degrees(),
                "diagonal".to_string(),
            )
        } else if has_fov {
            let fov = r.float("fov", 0.0)?;
            let axis = r
                .string("fov_axis")?
                .unwrap_or_else(|| "x".into())
                .to_ascii_lowercase();
            (fov, axis)
        } else {
            // Mitsuba's default: a 50 mm lens on the diagonal of 35 mm film.
            (
                2.0 * ((36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / 100.0)
                    .atan()
                    .to_degrees(),
                "diagonal".to_string(),
            )
        };
        let vfov_deg = vertical_fov(fov, &axis, aspect).ok_or_else(|| {
            self.fail(
                e,
                format!(
                    "fov {fov} along {axis}: the axis must be x, y, smaller, larger or diagonal \
                     and the field of view within (0, 180) degrees"
                ),
            )
        })?;
        let to_world = r.transform("to_world")?;
        for k in ["near_clip", "far_clip"] {
            if r.props.items.iter().any(|i| i.name == k) {
                r.float(k, 0.0)?;
                self.warn(e, format!("{k} ignored: luxest's camera does not clip"));
            }
        }
        // Mitsuba's perspective camera does not read it either (a pinhole has no focus).
        if r.props.items.iter().any(|i| i.name == "focus_distance") {
            r.float("focus_distance", 0.0)?;
            self.warn(e, "focus_distance ignored: a pinhole camera has no focus");
        }
        for k in ["principal_point_offset_x", "principal_point_offset_y"] {
            if r.float(k, 0.0)? != 0.0 {
                return Err(self.fail(e, format!("{k} other than 0 is not supported")));
            }
        }
        r.done()?;
        let m = &to_world.m;
        let col = |j: usize| Vec3::new(m[0][j], m[1][j], m[2][j]);
        let (x, y, z) = (col(0), col(1), col(2));
        let orthonormal = [
            (x, x, 1.0),
            (y, y, 1.0),
            (z, z, 1.0),
            (x, y, 0.0),
            (x, z, 0.0),
            (y, z, 0.0),
        ]
        .iter()
        .all(|(a, b, want)| (a.dot(*b) - want).abs() <= 1e-3);
        if !orthonormal {
            return Err(self.fail(
                e,
                "the camera's to_world has scale or shear (Mitsuba refuses it too)",
            ));
        }
        if to_world.determinant() < 0.0 {
            return Err(self.fail(
                e,
                "the camera's to_world mirrors the image (negative determinant), which luxest's \
                 camera cannot represent",
            ));
        }
        if self.scene.camera.is_some() {
            self.warn(e, "a second sensor: ignored (luxest renders one camera)");
            return Ok(());
        }
        let position = to_world.t;
        self.scene.camera = Some(Camera {
            position,
            look_at: position + z,
            up: y,
            vfov_deg,
            resolution: (width, height),
        });
        Ok(())
    }

    fn film(&self, e: &'a Elem) -> Result<(u32, u32)> {
        let plugin = e.attr("type").unwrap_or("");
        if plugin != "hdrfilm" {
            return Err(self.fail(e, format!("unsupported film \"{plugin}\" (only hdrfilm)")));
        }
        let r = self.reader(e)?;
        let w = r.integer("width", 768)?;
        let h = r.integer("height", 576)?;
        for k in ["file_format", "pixel_format", "component_format"] {
            r.string(k)?;
        }
        r.boolean("banner", true)?;
        r.boolean("sample_border", false)?;
        // Mitsuba 0.6 film options that Mitsuba 3 does not read either.
        for k in ["attach_log", "high_quality_edges", "gamma"] {
            if r.props.items.iter().any(|i| i.name == k) {
                if k == "gamma" {
                    r.float("gamma", 2.2)?;
                } else {
                    r.boolean(k, false)?;
                }
                self.warn(
                    e,
                    format!("{k} ignored (a Mitsuba 0.6 option Mitsuba 3 does not read)"),
                );
            }
        }
        for k in [
            "crop_offset_x",
            "crop_offset_y",
            "crop_width",
            "crop_height",
        ] {
            if r.props.items.iter().any(|i| i.name == k) {
                return Err(self.fail(e, format!("{k}: crop windows are not supported")));
            }
        }
        let filters = r.objects("rfilter");
        r.done()?;
        for f in filters {
            if f.attr("type") != Some("box") {
                self.warn(
                    f,
                    "luxest reconstructs pixels with a box filter; this filter is not applied",
                );
            }
        }
        let ok = |v: i64| (1..=crate::validate::MAX_RESOLUTION as i64).contains(&v);
        if !ok(w) || !ok(h) {
            return Err(self.fail(e, format!("film size {w}x{h} out of range")));
        }
        Ok((w as u32, h as u32))
    }

    fn top_level(&mut self, root: &'a Elem) -> Result<()> {
        for c in &root.children {
            match c.tag.as_str() {
                "shape" => self.shape(c)?,
                "emitter" => self.emitter(c)?,
                "sensor" => self.sensor(c)?,
                "bsdf" => {
                    // Translated (and checked) even when no shape uses it, as Mitsuba does.
                    self.material(c)?;
                }
                "texture" => {
                    self.texture(c)?;
                }
                "integrator" => self.warn(
                    c,
                    "ignored: luxest's estimators are chosen on its command line",
                ),
                "path" | "alias" => {}
                // Referred to from a sensor by id (and translated there); otherwise unused.
                "sampler" | "film" | "rfilter" => {
                    if c.attr("id").is_none() {
                        self.warn(c, "ignored: not inside a sensor");
                    }
                }
                "medium" | "phase" | "volume" => {
                    return Err(self.fail(c, format!("<{}> is not supported", c.tag)))
                }
                other => {
                    return Err(self.fail(c, format!("unknown element <{other}>")));
                }
            }
        }
        Ok(())
    }
}

/// The vertical field of view (degrees) of a Mitsuba `fov` along `axis` for an image of
/// width/height `aspect` (Mitsuba 3's `parse_fov`, then from x to y).
pub fn vertical_fov(fov: f64, axis: &str, aspect: f64) -> Option<f64> {
    let axis = match axis {
        "smaller" => {
            if aspect > 1.0 {
                "y"
            } else {
                "x"
            }
        }
        "larger" => {
            if aspect > 1.0 {
                "x"
            } else {
                "y"
            }
        }
        a => a,
    };
    let half = (0.5 * fov.to_radians()).tan();
    let tan_half_x = match axis {
        "x" => half,
        "y" => half * aspect,
        "diagonal" => half / (1.0 + 1.0 / (aspect * aspect)).sqrt(),
        _ => return None,
    };
    let x = 2.0 * tan_half_x.atan().to_degrees();
    if !(fov > 0.0 && fov < 180.0 && x > 0.0 && x < 180.0) {
        return None;
    }
    Some(2.0 * (tan_half_x / aspect).atan().to_degrees())
}

/// Collects every object element with an `id` (and `<alias>`es), refusing duplicates.
fn collect_ids<'a>(
    parser: &Parser,
    e: &'a Elem,
    ids: &mut BTreeMap<String, &'a Elem>,
) -> Result<()> {
    for c in &e.children {
        if c.tag == "alias" {
            let (Some(id), Some(alias)) = (c.attr("id"), c.attr("as")) else {
                return Err(Error::at(
                    &parser.files[c.file],
                    describe(c),
                    "needs id and as",
                ));
            };
            let Some(target) = ids.get(id).copied() else {
                return Err(Error::at(
                    &parser.files[c.file],
                    describe(c),
                    format!("no object has the id \"{id}\" (yet)"),
                ));
            };
            ids.insert(alias.to_string(), target);
            continue;
        }
        if matches!(c.tag.as_str(), "ref" | "transform") {
            continue;
        }
        if let Some(id) = c.attr("id") {
            if ids.insert(id.to_string(), c).is_some() {
                return Err(Error::at(
                    &parser.files[c.file],
                    describe(c),
                    format!("duplicate id \"{id}\""),
                ));
            }
        }
        collect_ids(parser, c, ids)?;
    }
    Ok(())
}

/// Translates the Mitsuba 3 scene file `path`.
pub fn import(path: &Path) -> Result<Imported> {
    import_impl(path, None, &[])
}

/// [`import`] with parameters given as Mitsuba's `-D name=value` gives them: they take
/// precedence over the scene's `<default>`s.
pub fn import_with(path: &Path, defines: &[(String, String)]) -> Result<Imported> {
    import_impl(path, None, defines)
}

/// [`import`] of the file's content `bytes`; `path` names it in errors and locates the files
/// it refers to (includes, meshes, maps).
pub fn import_bytes(path: &Path, bytes: &[u8]) -> Result<Imported> {
    import_impl(path, Some(bytes), &[])
}

fn import_impl(
    path: &Path,
    bytes: Option<&[u8]>,
    defines: &[(String, String)],
) -> Result<Imported> {
    let mut parser = Parser {
        files: Vec::new(),
        legacy: Vec::new(),
        params: defines.to_vec(),
        stack: Vec::new(),
    };
    let root = parser.parse_file_bytes(path, bytes, None)?;
    if root.tag != "scene" {
        return Err(Error::at(
            path,
            describe(&root),
            "the root element must be <scene>",
        ));
    }
    let mut ids = BTreeMap::new();
    collect_ids(&parser, &root, &mut ids)?;
    let mut search = Vec::new();
    for c in root.children.iter().filter(|c| c.tag == "path") {
        let dir = parser.files[c.file].parent().unwrap_or(Path::new("."));
        search.push(dir.join(c.attr("value").unwrap_or("")));
    }
    let mut imp = Importer {
        parser: &parser,
        ids,
        scene: super::empty_scene(),
        warnings: RefCell::new(Vec::new()),
        materials: BTreeMap::new(),
        default_bsdf: None,
        textures: RefCell::new(BTreeMap::new()),
        texture_names: RefCell::new(BTreeMap::new()),
        bsdf_depth: Cell::new(0),
        search,
    };
    imp.top_level(&root)?;
    imp.scene.textures = imp.textures.take();
    Ok(Imported {
        scene: imp.scene,
        warnings: imp.warnings.into_inner(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camel_case_becomes_snake_case_as_mitsuba_upgrades_it() {
        assert_eq!(camel_to_snake("toWorld"), "to_world");
        assert_eq!(camel_to_snake("intIOR"), "int_ior");
        assert_eq!(camel_to_snake("fovAxis"), "fov_axis");
        assert_eq!(camel_to_snake("radiance"), "radiance");
    }

    #[test]
    fn vertical_fov_matches_mitsubas_parse_fov() {
        // Mitsuba's own test (src/render/tests/test_sensor.py): fov 35 along y at aspect 0.5
        // is an x fov of 17.87 degrees; here the y fov must come back as 35.
        assert!((vertical_fov(35.0, "y", 0.5).unwrap() - 35.0).abs() < 1e-12);
        // Along x at aspect 2: tan(v/2) = tan(x/2) / 2.
        let v = vertical_fov(90.0, "x", 2.0).unwrap();
        assert!((v - 2.0 * 0.5f64.atan().to_degrees()).abs() < 1e-12);
        // Diagonal of a square: tan(v/2) = tan(d/2) / sqrt 2.
        let v = vertical_fov(60.0, "diagonal", 1.0).unwrap();
        let want = 2.0
            * ((30f64).to_radians().tan() / 2f64.sqrt())
                .atan()
                .to_degrees();
        assert!((v - want).abs() < 1e-12);
        assert_eq!(
            vertical_fov(40.0, "smaller", 2.0),
            vertical_fov(40.0, "y", 2.0)
        );
        assert!(vertical_fov(40.0, "z", 1.0).is_none());
    }

    #[test]
    fn rotation_is_right_handed() {
        let r = rotation(Vec3::new(0.0, 0.0, 1.0), 90.0);
        let p = r.apply_point(Vec3::new(1.0, 0.0, 0.0));
        assert!((p - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-15);
    }
}
