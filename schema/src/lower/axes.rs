//! What a world says before its nodes are typed: its up axis and object convention (see
//! `crate::webots`), its Webots version and `WorldInfo.randomSeed`, which templates see.

use regatta_parser::syntax::{self, Atom, BodyItem, Dialect, Item, Items, NodeKind};

use crate::scene::UpAxis;

use super::state::Lowerer;

impl<'c> Lowerer<'c> {
    /// The world's up axis and object convention (see [`crate::webots`]), read before its
    /// nodes are typed: `WorldInfo.coordinateSystem` if written, else the header.
    pub(super) fn decide_axes(
        &mut self,
        header: Option<&syntax::Header>,
        parsed: &syntax::SourceFile,
    ) {
        let mut declared = None;
        for item in &parsed.items {
            let Item::Node(syntax::Node {
                kind:
                    NodeKind::Instance {
                        type_name,
                        body: Some(body),
                    },
                ..
            }) = item
            else {
                continue;
            };
            if type_name.text != "WorldInfo" {
                continue;
            }
            for field in &body.items {
                if let BodyItem::Field(f) = field {
                    if f.name.text == "randomSeed" {
                        if let syntax::FieldValue::Value(syntax::Value {
                            items: Items::Numbers(list),
                            ..
                        }) = &f.value
                        {
                            if let Some(&seed) = list.values.first() {
                                self.world_seed = seed as i64;
                            }
                        }
                    }
                    if f.name.text == "coordinateSystem" {
                        if let syntax::FieldValue::Value(syntax::Value {
                            items: Items::Atoms(atoms),
                            ..
                        }) = &f.value
                        {
                            if let Some(Atom::String(system)) = atoms.first() {
                                declared = Some(system.value.clone());
                            }
                        }
                    }
                }
            }
        }
        self.webots_version = match header {
            Some(syntax::Header {
                dialect: Dialect::Webots,
                version,
                ..
            }) => version.clone(),
            // Files that are not Webots': the release regatta's stand-ins are written for.
            _ => "R2023b".to_owned(),
        };
        // (year, letter) of a Webots header.
        let version = match header {
            Some(syntax::Header {
                dialect: Dialect::Webots,
                version,
                ..
            }) => version.strip_prefix('R').and_then(|v| {
                let year = v.get(..4)?.parse::<u32>().ok()?;
                let letter = v[4..].chars().next().unwrap_or('a');
                Some((year, letter))
            }),
            _ => None,
        };
        self.up_axis = match declared.as_deref() {
            Some("NUE" | "EUN") => UpAxis::Y,
            Some("ENU") => UpAxis::Z,
            // WorldInfo.coordinateSystem appeared in R2020b with "ENU" as its default.
            _ => match version {
                Some(v) if v >= (2020, 'b') => UpAxis::Z,
                _ => UpAxis::Y,
            },
        };
        self.objects = match (self.up_axis, version) {
            (UpAxis::Z, Some(v)) if v >= (2022, 'a') => crate::webots::Objects::Flu,
            // A y-up file of R2022a or later is Webots' when it declares its PROTOs (Webots
            // writes an EXTERNPROTO line for each since R2022b, as its API tests have); one
            // without any is written by hand in the y-up convention (regatta's own worlds).
            (UpAxis::Y, Some(v))
                if v >= (2022, 'a')
                    && parsed
                        .items
                        .iter()
                        .any(|item| matches!(item, Item::ExternProto(_))) =>
            {
                crate::webots::Objects::FluYUp
            }
            _ => crate::webots::Objects::Legacy,
        };
    }
}
