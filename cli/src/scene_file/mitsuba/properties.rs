//! The properties of a Mitsuba object: typed values read from its child
//! elements, each marked when a plugin reads it so that the ones no plugin
//! knows are reported.
//!
//! An object element (`<bsdf type="diffuse">`, `<shape>`, …) has property
//! children (`<float name value>`, `<rgb>`, `<spectrum>`, `<transform>`,
//! …) and nested objects (`<bsdf>`, `<texture>`, `<emitter>`, `<ref>`,
//! `<rfilter>`, …, named by a `name` attribute or not). Values are parsed
//! as Mitsuba 3.9.1's `xml.cpp` does: numbers as in C (`1`, `-2.5e3`), NaN
//! and infinities refused; booleans `true`/`false` (any case); lists of
//! numbers separated by commas and/or white space; `<point>`/`<vector>`
//! with `x`, `y`, `z` (missing ones 0) or `value` (one or three numbers).
//! A `<spectrum>` with a `type` or with children is an object (a plugin
//! such as `blackbody`), else a property (`value` or `filename`).

use super::document::Element;
use super::transforms::read_transform;
use crate::error::CliError;
use glam::Vec3;
use simd_tracer::scene::transform::Transform;
use std::cell::Cell;

/// A property's value.
#[derive(Debug, Clone)]
pub(crate) enum Value<'e> {
    /// `<integer>`.
    Integer(i64),
    /// `<float>`.
    Float(f64),
    /// `<boolean>`.
    Boolean(bool),
    /// `<string>`.
    String(&'e str),
    /// `<point>` or `<vector>`.
    Vector(Vec3),
    /// `<rgb>` (one value repeated, or three).
    Rgb([f64; 3]),
    /// `<spectrum value="…">`: the attribute text, parsed where it is used.
    SpectrumText(&'e str),
    /// `<spectrum filename="…">`.
    SpectrumFile(&'e str),
    /// `<transform>`.
    Transform(Transform),
    /// A nested object.
    Object(&'e Element),
    /// `<ref id>`: the id.
    Ref(&'e str),
}

impl Value<'_> {
    /// What the value is, for messages.
    pub(crate) fn kind(&self) -> &'static str {
        match self {
            Self::Integer(_) => "an integer",
            Self::Float(_) => "a float",
            Self::Boolean(_) => "a boolean",
            Self::String(_) => "a string",
            Self::Vector(_) => "a point/vector",
            Self::Rgb(_) => "an rgb value",
            Self::SpectrumText(_) | Self::SpectrumFile(_) => "a spectrum",
            Self::Transform(_) => "a transform",
            Self::Object(_) => "an object",
            Self::Ref(_) => "a reference",
        }
    }
}

/// One property or nested object of an object.
#[derive(Debug)]
pub(crate) struct Property<'e> {
    /// Its `name` (empty for an unnamed nested object).
    pub(crate) name: &'e str,
    /// Its value.
    pub(crate) value: Value<'e>,
    /// The element it was given by.
    pub(crate) element: &'e Element,
    used: Cell<bool>,
}

/// An object element with its properties.
#[derive(Debug)]
pub(crate) struct Object<'e> {
    /// The element.
    pub(crate) element: &'e Element,
    /// Its `type` (plugin name; empty when absent).
    pub(crate) plugin: &'e str,
    /// Its properties and nested objects, in document order.
    pub(crate) properties: Vec<Property<'e>>,
}

/// Tags of nested objects.
pub(crate) const OBJECT_TAGS: &[&str] = &[
    "bsdf",
    "texture",
    "emitter",
    "shape",
    "sensor",
    "film",
    "sampler",
    "rfilter",
    "integrator",
    "medium",
    "phase",
    "volume",
];

impl<'e> Object<'e> {
    /// The object of `element`: its properties parsed (errors at their
    /// elements).
    pub(crate) fn new(element: &'e Element) -> Result<Self, CliError> {
        let mut properties = Vec::with_capacity(element.children.len());
        for child in &element.children {
            let name = child.attr("name").unwrap_or("");
            let value = property_value(child)?;
            if name.is_empty() && !matches!(value, Value::Object(_) | Value::Ref(_)) {
                return Err(child.error(format!("<{}> needs a `name`", child.tag)));
            }
            if !name.is_empty() && properties.iter().any(|p: &Property<'_>| p.name == name) {
                return Err(child.error(format!(
                    "property \"{name}\" is given twice in this <{}>",
                    element.tag
                )));
            }
            properties.push(Property {
                name,
                value,
                element: child,
                used: Cell::new(false),
            });
        }
        Ok(Self {
            element,
            plugin: element.attr("type").unwrap_or(""),
            properties,
        })
    }

    /// `<tag type="plugin">` for messages.
    pub(crate) fn describe(&self) -> String {
        format!("{} \"{}\"", self.element.tag, self.plugin)
    }

    /// An input error at the object.
    pub(crate) fn error(&self, message: impl std::fmt::Display) -> CliError {
        self.element
            .error(format!("{}: {message}", self.describe()))
    }

    /// The property `name`, marked used.
    pub(crate) fn get(&self, name: &str) -> Option<&Property<'e>> {
        let p = self.properties.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// The unnamed nested objects with tag `tag`, references included
    /// (`tag_of` names the tag of the element a reference's id names), each
    /// marked used; an unnamed object or reference of another tag is left
    /// for its own reader (a sensor's `<ref>` may name its sampler or its
    /// film).
    pub(crate) fn nested(
        &self,
        tag: &str,
        mut tag_of: impl FnMut(&Property<'e>, &'e str) -> Result<&'e str, CliError>,
    ) -> Result<Vec<&Property<'e>>, CliError> {
        let mut found = Vec::new();
        for p in self.properties.iter().filter(|p| p.name.is_empty()) {
            let matches = match p.value {
                Value::Object(e) => e.tag == tag,
                Value::Ref(id) => tag_of(p, id)? == tag,
                _ => false,
            };
            if matches {
                p.used.set(true);
                found.push(p);
            }
        }
        Ok(found)
    }

    /// Every nested object and reference (named or not), marked used.
    pub(crate) fn objects(&self) -> Vec<&Property<'e>> {
        self.properties
            .iter()
            .filter(|p| matches!(p.value, Value::Object(_) | Value::Ref(_)))
            .inspect(|p| p.used.set(true))
            .collect()
    }

    /// Marks `names` as read though the importer ignores them (parameters
    /// that do not change the image, such as a film's pixel format).
    pub(crate) fn ignore(&self, names: &[&str]) {
        for p in &self.properties {
            if names.contains(&p.name) {
                p.used.set(true);
            }
        }
    }

    /// The properties nothing read (after the plugin has read its own).
    pub(crate) fn unused(&self) -> impl Iterator<Item = &Property<'e>> {
        self.properties.iter().filter(|p| !p.used.get())
    }

    /// A float property (integers accepted), or `default`.
    pub(crate) fn float(&self, name: &str, default: f64) -> Result<f64, CliError> {
        Ok(self.float_opt(name)?.unwrap_or(default))
    }

    /// A float property (integers accepted), if given.
    pub(crate) fn float_opt(&self, name: &str) -> Result<Option<f64>, CliError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Float(v) => Ok(Some(v)),
                Value::Integer(v) => Ok(Some(v as f64)),
                ref other => Err(p.wrong_type("a float", other)),
            },
        }
    }

    /// An integer property, or `default`.
    pub(crate) fn integer(&self, name: &str, default: i64) -> Result<i64, CliError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Integer(v) => Ok(v),
                ref other => Err(p.wrong_type("an integer", other)),
            },
        }
    }

    /// A boolean property, or `default`.
    pub(crate) fn boolean(&self, name: &str, default: bool) -> Result<bool, CliError> {
        match self.get(name) {
            None => Ok(default),
            Some(p) => match p.value {
                Value::Boolean(v) => Ok(v),
                ref other => Err(p.wrong_type("a boolean", other)),
            },
        }
    }

    /// A string property, if given.
    pub(crate) fn string(&self, name: &str) -> Result<Option<&'e str>, CliError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::String(v) => Ok(Some(v)),
                ref other => Err(p.wrong_type("a string", other)),
            },
        }
    }

    /// The required `filename` parameter, resolved against the file's
    /// folder (the `<path>` folders included).
    pub(crate) fn filename(&self) -> Result<std::path::PathBuf, CliError> {
        let name = self
            .string("filename")?
            .ok_or_else(|| self.error("needs `filename`"))?;
        self.element.place.resolve(name).ok_or_else(|| {
            self.error(format!(
                "\"{name}\": file references are not available here"
            ))
        })
    }

    /// A point or vector property, if given.
    pub(crate) fn vector(&self, name: &str) -> Result<Option<Vec3>, CliError> {
        match self.get(name) {
            None => Ok(None),
            Some(p) => match p.value {
                Value::Vector(v) => Ok(Some(v)),
                ref other => Err(p.wrong_type("a point or vector", other)),
            },
        }
    }

    /// A transform property, or the identity.
    pub(crate) fn transform(&self, name: &str) -> Result<Transform, CliError> {
        match self.get(name) {
            None => Ok(Transform::IDENTITY),
            Some(p) => match &p.value {
                Value::Transform(t) => Ok(*t),
                other => Err(p.wrong_type("a transform", other)),
            },
        }
    }
}

impl Property<'_> {
    /// An input error at the property.
    pub(crate) fn error(&self, message: impl std::fmt::Display) -> CliError {
        if self.name.is_empty() {
            self.element.error(message)
        } else {
            self.element
                .error(format!("property \"{}\": {message}", self.name))
        }
    }

    /// The error of a value of the wrong type.
    pub(crate) fn wrong_type(&self, expected: &str, got: &Value<'_>) -> CliError {
        self.error(format!("expected {expected}, got {}", got.kind()))
    }
}

/// The value of a child element of an object.
fn property_value(e: &Element) -> Result<Value<'_>, CliError> {
    let value = || {
        e.attr("value")
            .ok_or_else(|| e.error(format!("<{}> needs `value`", e.tag)))
    };
    Ok(match e.tag.as_str() {
        "integer" => {
            let text = value()?;
            Value::Integer(
                text.trim()
                    .parse::<i64>()
                    .map_err(|_| e.error(format!("<integer>: \"{text}\" is not an integer")))?,
            )
        }
        "float" => Value::Float(parse_number(e, value()?)?),
        "boolean" => {
            let text = value()?;
            Value::Boolean(match text.trim().to_ascii_lowercase().as_str() {
                "true" => true,
                "false" => false,
                _ => {
                    return Err(e.error(format!("<boolean>: \"{text}\" is neither true nor false")));
                }
            })
        }
        "string" => Value::String(value()?),
        "point" | "vector" => Value::Vector(parse_vector(e)?),
        "rgb" => {
            let numbers = parse_numbers(e, value()?)?;
            Value::Rgb(match numbers.as_slice() {
                [v] => [*v; 3],
                [r, g, b] => [*r, *g, *b],
                _ => {
                    return Err(
                        e.error(format!("<rgb> needs 1 or 3 values, got {}", numbers.len()))
                    );
                }
            })
        }
        "spectrum" if e.attr("type").is_none() && e.children.is_empty() => {
            match (e.attr("value"), e.attr("filename")) {
                (Some(v), None) => Value::SpectrumText(v),
                (None, Some(f)) => Value::SpectrumFile(f),
                _ => {
                    return Err(e.error(
                        "<spectrum> needs exactly one of `value` and `filename` (or a `type`)",
                    ));
                }
            }
        }
        "spectrum" => Value::Object(e),
        "transform" => Value::Transform(read_transform(e)?),
        "ref" => Value::Ref(e.attr("id").ok_or_else(|| e.error("<ref> needs `id`"))?),
        tag if OBJECT_TAGS.contains(&tag) => Value::Object(e),
        tag => return Err(e.error(format!("unknown element <{tag}>"))),
    })
}

/// A finite number as C's `strtod` reads it (no NaN or infinity, nothing
/// beyond `f32`'s range).
pub(crate) fn parse_number(e: &Element, text: &str) -> Result<f64, CliError> {
    let trimmed = text.trim();
    let lower = trimmed.to_ascii_lowercase();
    let v = if lower.contains("inf") || lower.contains("nan") {
        None
    } else {
        trimmed.parse::<f64>().ok()
    };
    // Values beyond f32's range would become infinite in the scene.
    v.filter(|v| (*v as f32).is_finite())
        .ok_or_else(|| e.error(format!("\"{text}\" is not a finite number")))
}

/// Numbers separated by commas and/or white space.
pub(crate) fn parse_numbers(e: &Element, text: &str) -> Result<Vec<f64>, CliError> {
    text.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| parse_number(e, s))
        .collect()
}

/// `x`, `y`, `z` attributes (missing ones 0) or `value` (one number for
/// all three, or three).
pub(crate) fn parse_vector(e: &Element) -> Result<Vec3, CliError> {
    if let Some(text) = e.attr("value") {
        let n = parse_numbers(e, text)?;
        return match n.as_slice() {
            [v] => Ok(Vec3::splat(*v as f32)),
            [x, y, z] => Ok(Vec3::new(*x as f32, *y as f32, *z as f32)),
            _ => Err(e.error(format!(
                "<{}> `value` needs 1 or 3 numbers, got {}",
                e.tag,
                n.len()
            ))),
        };
    }
    let axis = |name: &str| -> Result<f32, CliError> {
        e.attr(name)
            .map_or(Ok(0.0), |t| parse_number(e, t).map(|v| v as f32))
    };
    Ok(Vec3::new(axis("x")?, axis("y")?, axis("z")?))
}
