// kdmesh — the gear box model (mm): an assembly of a housing, a shaft, a spur gear on it and two
// bearing rings holding the shaft in the housing's bores, each its own closed body; the parts
// touch where they should (ring | housing, ring | shaft, gear | shaft) on coincident faces.
// SPDX-License-Identifier: AGPL-3.0-or-later
//
// Regenerate with models/generate.sh (do not edit gearbox.stl by hand).
//
// Frame (mm): x in [-100, 100] (length, feet included), y in [-75, 75] (bearing axis, bosses
// included), z in [0, 150] (height; the feet stand on z = 0). The bearing axis is the line
// x = 0, z = 75, parallel to y. The gear turns about that axis inside the cavity.
//
// Housing: box [-85,85] x [-60,60] x [0,150], wall 8; cavity [-77,77] x [-52,52] x [8,142].
//   Bosses r = 28 around the bearing axis out to |y| = 75, bores r = 18 through them and the
//   walls. Outside ribs: two vertical ones on each y wall (x = +-45) and one under each boss,
//   two on each x wall (y = +-30). Feet on both x ends, x in [84,100] (mirrored), z in [0,14],
//   two bolt holes r = 5.5 in each.
// Gear: 26 teeth, module 4 (pitch radius 52, tip radius 56, root radius 47), face width 30
//   (|y| <= 15), web 12 thick (|y| <= 6) between r = 24 and the rim r = 40 with 6 lightening
//   holes r = 6.5, hub r = 24 for |y| <= 30, bore r = 10.
// Clearances gear <-> housing: 11 mm to floor and roof (z 19..131 vs 8..142), 21 mm to the
//   x walls, 22 mm from the hub ends to the y walls (|y| 30 vs 52).
// Shaft: r = 10 (the gear's bore) about the bearing axis, |y| <= 85 (out of both bosses).
// Bearing rings: r = 10 to 18 (the shaft to the bore), 55 <= |y| <= 71 (in the wall and boss).
// Coincident faces are made of the same vertices: every cylinder is $fn = 64 about the same
// axis, turned by the same rotate([-90, 0, 0]), so the parts' STLs share their coordinates.
//
// `part` selects what is rendered: "housing", "gear", "shaft", "bearing_a" (y < 0),
// "bearing_b" (y > 0), one STL each (the assembly, models/gearbox/gearbox.yaml), or
// "housing_gear": housing and gear in one file (gearbox.stl: the input of the paper-table and
// TetGen comparisons, docs/tetgen_comparison.md).
part = "housing_gear";

$fn = 64;

module housing() {
  difference() {
    union() {
      translate([-85, -60, 0]) cube([170, 120, 150]);
      // bosses around the bearing axis, both sides
      for (s = [-1, 1])
        translate([0, s * 59, 75]) rotate([s * -90, 0, 0]) cylinder(r = 28, h = 16);
      // vertical ribs on the y walls
      for (s = [-1, 1]) for (x = [-45, 45])
        translate([x - 3, s > 0 ? 59 : -70, 0]) cube([6, 11, 135]);
      // ribs under the bosses (they end inside the boss)
      for (s = [-1, 1])
        translate([-3, s > 0 ? 59 : -73, 0]) cube([6, 14, 60]);
      // vertical ribs on the x walls
      for (s = [-1, 1]) for (y = [-30, 30])
        translate([s > 0 ? 84 : -95, y - 3, 0]) cube([11, 6, 130]);
      // mounting feet
      for (s = [-1, 1])
        translate([s > 0 ? 84 : -100, -60, 0]) cube([16, 120, 14]);
    }
    // cavity
    translate([-77, -52, 8]) cube([154, 104, 134]);
    // bearing bores, through bosses and walls into the cavity
    translate([0, -80, 75]) rotate([-90, 0, 0]) cylinder(r = 18, h = 160);
    // bolt holes in the feet
    for (s = [-1, 1]) for (y = [-48, 48])
      translate([s * 93, y, -1]) cylinder(r = 5.5, h = 16);
  }
}

// Involute spur gear profile (2-D, in the xy plane, centred at the origin).
teeth = 26;
module_m = 4;
pitch_r = teeth * module_m / 2;  // 52
tip_r = pitch_r + module_m;      // 56
root_r = pitch_r - 1.25 * module_m;  // 47
base_r = pitch_r * cos(20);      // 48.86

function inv(a) = tan(a) - a * PI / 180;  // involute function, a in degrees, result radians
// polar angle (degrees) of the involute point at radius r, measured from the tooth's
// flank origin on the base circle
function inv_angle(r) = let(a = acos(base_r / r)) inv(a) * 180 / PI;
// half tooth thickness angle at the base circle (degrees)
half_base = 90 / teeth + inv_angle(pitch_r);

module gear_profile() {
  nf = 8;  // points per flank
  pts = [for (k = [0 : teeth - 1])
    let(c = k * 360 / teeth)
    each concat(
      // root point before the tooth, then the right flank (from base circle up to tip)
      [[root_r * cos(c - half_base - 2), root_r * sin(c - half_base - 2)]],
      [for (i = [0 : nf]) let(r = base_r + (tip_r - base_r) * i / nf,
                              t = c - half_base + inv_angle(r))
         [r * cos(t), r * sin(t)]],
      // left flank from tip down to base circle
      [for (i = [nf : -1 : 0]) let(r = base_r + (tip_r - base_r) * i / nf,
                                   t = c + half_base - inv_angle(r))
         [r * cos(t), r * sin(t)]],
      [[root_r * cos(c + half_base + 2), root_r * sin(c + half_base + 2)]]
    )];
  polygon(pts);
}

module gear() {
  // axis along y through (0, *, 75)
  translate([0, 0, 75]) rotate([-90, 0, 0]) difference() {
    union() {
      // toothed rim
      translate([0, 0, -15]) difference() {
        linear_extrude(height = 30) gear_profile();
        translate([0, 0, -1]) cylinder(r = 40, h = 32);
      }
      // web
      translate([0, 0, -6]) cylinder(r = 41, h = 12);
      // hub
      translate([0, 0, -30]) cylinder(r = 24, h = 60);
    }
    translate([0, 0, -31]) cylinder(r = 10, h = 62);
    for (k = [0 : 5])
      rotate([0, 0, 30 + k * 60]) translate([32, 0, -7]) cylinder(r = 6.5, h = 14);
  }
}

module shaft() {
  translate([0, -85, 75]) rotate([-90, 0, 0]) cylinder(r = 10, h = 170);
}

module bearing(s) {
  translate([0, s > 0 ? 55 : -71, 75]) rotate([-90, 0, 0]) difference() {
    cylinder(r = 18, h = 16);
    translate([0, 0, -1]) cylinder(r = 10, h = 18);
  }
}

if (part == "housing" || part == "housing_gear") housing();
if (part == "gear" || part == "housing_gear") gear();
if (part == "shaft") shaft();
if (part == "bearing_a") bearing(-1);
if (part == "bearing_b") bearing(1);
