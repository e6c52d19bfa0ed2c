//! The sandbox: composition as Webots does it, Webots' value shapes and modules, errors placed
//! in the template, limits, and nothing from outside (files, clock, host randomness).

use regatta_template::{Engine, Generated, Limits, Request, TemplateError};

fn expand_with(
    content: &str,
    fields: serde_json::Value,
    seed: u32,
) -> Result<Generated, TemplateError> {
    let engine = Engine::new(Limits::default()).unwrap();
    let context = serde_json::json!({"id": 4, "coordinate_system": "ENU"});
    engine.expand(&Request {
        content,
        name: "Test.proto",
        fields: &fields,
        context: &context,
        seed,
    })
}

fn expand(content: &str) -> Result<Generated, TemplateError> {
    let fields = serde_json::json!({
        "n": {"value": 3, "defaultValue": 2},
        "size": {"value": {"x": 1, "y": 2, "z": 3}, "defaultValue": {"x": 0.1, "y": 0.1, "z": 0.1}},
        "colors": {"value": [{"r": 1, "g": 0, "b": 0}], "defaultValue": []},
        "geometry": {"value": {"node_name": "Box", "fields": {"size": {"value": {"x": 2, "y": 2, "z": 2}, "defaultValue": {"x": 2, "y": 2, "z": 2}}}}, "defaultValue": null},
    });
    expand_with(content, fields, 7)
}

fn text(content: &str) -> String {
    match expand(content) {
        Ok(generated) => generated.text,
        Err(error) => panic!("{content}: {error:?}"),
    }
}

#[test]
fn statements_wrap_text_and_expressions_write_values() {
    assert_eq!(
        text("Group { %< for (let i = 0; i < fields.n.value; ++i) { >%a%<= i * 2 >% %< } >%}"),
        "Group { a0 a2 a4 }"
    );
    // Webots' "technically correct, but risky" form: one statement per text stretch.
    assert_eq!(
        text("%< if (fields.n.value > 2) >%\n radius 1\n%< else >%\n radius 2\n"),
        "\n radius 1\n"
    );
    // A comment of the PROTO text hides the blocks on its line; strings hold blocks.
    assert_eq!(
        text("# %<= 1 >%\nurl \"%<= 'a' + 1 >%.png\""),
        "# %<= 1 >%\nurl \"a1.png\""
    );
    assert_eq!(
        text("%<= fields.size.value.z - fields.size.defaultValue.x >%"),
        "2.9"
    );
    assert_eq!(
        text("%<= fields.colors.value[0].r >% %<= fields.colors.defaultValue.length >%"),
        "1 0"
    );
    assert_eq!(
        text("%<= fields.geometry.value.node_name >% %<= fields.geometry.value.fields.size.value.y >%"),
        "Box 2"
    );
    assert_eq!(
        text("%<= context.id >% %<= context.coordinate_system >%"),
        "4 ENU"
    );
}

#[test]
fn webots_modules_import_and_behave() {
    let circle = text(
        "%< import * as wbgeometry from 'wbgeometry.js'; const c = wbgeometry.circle(2, 4, {x: 1, y: 0}, 0); >%\
         %<= c.length >% %<= c[1].x.toFixed(6) >% %<= c[1].y >%",
    );
    assert_eq!(circle, "4 1.000000 2");
    assert_eq!(
        text("%< import {isPoint2InPolygon, isPoint2ArrayClockwise} from 'wbgeometry.js'; \
              const square = [{x: 0, y: 0}, {x: 1, y: 0}, {x: 1, y: 1}, {x: 0, y: 1}]; >%\
              %<= isPoint2InPolygon({x: 0.5, y: 0.5}, square) >% %<= isPoint2InPolygon({x: 2, y: 0.5}, square) >% \
              %<= isPoint2ArrayClockwise(square) >%"),
        "true false false"
    );
    let spline = text(
        "%< import * as g from 'wbgeometry.js'; \
         const s = g.bSpline2([{x: 0, y: 0}, {x: 1, y: 1}, {x: 2, y: 0}], 4); >%\
         %<= s.length >% %<= JSON.stringify(s[0]) >% %<= JSON.stringify(s[s.length - 1]) >%",
    );
    assert_eq!(spline, "17 {\"x\":0,\"y\":0} {\"x\":2,\"y\":0}");
    assert_eq!(
        text(
            "%< import * as v from 'wbvector3.js'; import * as v2 from 'wbvector2.js'; >%\
              %<= JSON.stringify(v.cross({x: 1, y: 0, z: 0}, {x: 0, y: 1, z: 0})) >% \
              %<= v2.norm(v2.minus({x: 4, y: 3}, {x: 0, y: 0})) >%"
        ),
        "{\"x\":0,\"y\":0,\"z\":1} 5"
    );
    let turned = text(
        "%< import * as r from 'wbrotation.js'; \
         const v = r.rotateVector3ByRotation({x: 0, y: 0, z: 1, a: Math.PI / 2}, {x: 1, y: 0, z: 0}); \
         const back = r.fromMatrix3(r.toMatrix3({x: 0, y: 1, z: 0, a: 0.5})); >%\
         %<= v.x.toFixed(9) >% %<= v.y.toFixed(9) >% %<= back.y.toFixed(9) >% %<= back.a.toFixed(9) >% \
         %<= r.equal(r.combine({x: 0, y: 0, z: 1, a: 1}, {x: 0, y: 0, z: 1, a: 2}), {x: 0, y: 0, z: 1, a: 3}) >%",
    );
    assert_eq!(
        turned,
        "0.000000000 1.000000000 1.000000000 0.500000000 true"
    );
    assert_eq!(
        text(
            "%< import * as u from 'wbutility.js'; >%%<= u.radiansToDegrees(Math.PI) >% \
              %<= u.isVector3(fields.size.value) >% %<= u.isAxisAngle(fields.size.value) >%"
        ),
        "180 true false"
    );
}

#[test]
fn randomness_is_seeded_and_the_clock_stands_still() {
    let content = "%< import * as wbrandom from 'wbrandom.js'; >%\
                   %<= wbrandom.integer(0, 1000) >% %<= wbrandom.real(-1, 1) >% %<= Math.random() >% %<= Date.now() >%";
    let fields = serde_json::json!({});
    let a = expand_with(content, fields.clone(), 1).unwrap().text;
    assert_eq!(a, expand_with(content, fields.clone(), 1).unwrap().text);
    assert_ne!(a, expand_with(content, fields.clone(), 2).unwrap().text);
    // An explicit seed gives the same numbers whatever regatta's seed.
    let seeded = "%< import * as wbrandom from 'wbrandom.js'; wbrandom.seed(42); >%%<= wbrandom.integer(9) >%";
    assert_eq!(
        expand_with(seeded, fields.clone(), 1).unwrap().text,
        expand_with(seeded, fields.clone(), 2).unwrap().text
    );
    let integers = text(
        "%< import * as wbrandom from 'wbrandom.js'; let seen = new Set(); \
         for (let i = 0; i < 1000; ++i) seen.add(wbrandom.integer(3, 5)); >%%<= [...seen].sort().join(',') >%",
    );
    assert_eq!(integers, "3,4,5");
    assert_eq!(
        text("%<= new Date().getTime() === Date.now() >% %<= new Date(2021, 5, 1).getHours() >% %<= new Date().getTimezoneOffset() >%"),
        "true 0 0"
    );
}

#[test]
fn math_is_the_same_everywhere() {
    // libm's results, which the platform's own functions need not match.
    let value: f64 = text("%<= Math.sin(1e22) >%").parse().unwrap();
    assert_eq!(value, libm::sin(1e22));
    assert_eq!(text("%<= Math.pow(1, NaN) >% %<= Math.pow(2, 10) >% %<= Math.atan2(1, 1) * 4 === Math.PI >%"), "NaN 1024 true");
}

#[test]
fn console_lines_are_kept() {
    let generated =
        expand("%< console.log('made', fields.n.value, {a: 1}); console.warn('careful'); >%ok")
            .unwrap();
    assert_eq!(generated.text, "ok");
    assert_eq!(generated.console.len(), 2);
    assert_eq!(generated.console[0].text, "made 3 {\"a\":1}");
    assert!(!generated.console[0].warning && generated.console[1].warning);
}

#[test]
fn errors_are_placed_in_the_template() {
    let content = "Box {\n  size %< let x = ; >% 1 1 1\n}";
    let error = expand(content).unwrap_err();
    assert!(error.message.starts_with("SyntaxError"), "{error:?}");
    assert_eq!(error.offset, content.find(';'));

    let content = "Box {\n  %< const g = fields.nothing.value; >%\n}";
    let error = expand(content).unwrap_err();
    assert_eq!(
        error.message,
        "TypeError: cannot read property 'value' of undefined"
    );
    assert_eq!(error.offset, content.find("fields.nothing"));

    let content = "%< import * as fs from 'fs.js'; >%";
    let error = expand(content).unwrap_err();
    assert!(
        error.message.starts_with("cannot import 'fs.js'"),
        "{error:?}"
    );
    assert_eq!(error.offset, content.find("'fs.js'"));

    let error = expand("a %< if (x) { ").unwrap_err();
    assert_eq!(error.offset, Some(2));
    assert!(error.message.contains("never closed"));

    let error = expand("%< throw 'plain'; >%").unwrap_err();
    assert_eq!(error.message, "the template threw plain");
}

#[test]
fn nothing_reaches_outside() {
    for content in [
        "%< wbfile.readTextFile('/etc/passwd'); >%",
        "%< wbfile.writeTextFile('x', 'y'); >%",
        "%< import * as os from 'os'; >%",
        "%< import * as std from 'std'; >%",
        "%< import * as e from 'wbenv.js'; >%",
    ] {
        assert!(expand(content).is_err(), "{content}");
    }
    assert_eq!(
        text("%<= typeof require >% %<= typeof process >% %<= typeof fetch >%"),
        "undefined undefined undefined"
    );
}

#[test]
fn limits_stop_runaway_templates() {
    let error = expand("%< while (true) {} >%").unwrap_err();
    assert!(error.message.contains("work limit"), "{error:?}");
    let error =
        expand("%< let a = []; for (;;) a.push('x'.repeat(1000) + a.length); >%").unwrap_err();
    assert!(error.message.contains("out of memory"), "{error:?}");
    let error = expand("%< function f() { return f() + 1; } f(); >%").unwrap_err();
    assert!(error.message.starts_with("RangeError"), "{error:?}");
    // The engine is still usable after each.
    assert_eq!(text("%<= 1 + 1 >%"), "2");
}
