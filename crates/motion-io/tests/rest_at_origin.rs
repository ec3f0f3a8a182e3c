//! `with_rest_at_origin`: a BVH whose root OFFSET holds the capture volume's position (as the Bandai
//! files' `Hips` does, 4.3 m from the origin) gets its rest pose over the origin, keeps every other
//! OFFSET, and animates exactly as before.

use motion_io::{parse_bvh, to_bvh_string, with_rest_at_origin};

const BANDAI_LIKE: &str = "HIERARCHY
ROOT joint_Root
{
 OFFSET 0 0 0
 CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
 JOINT Hips
 {
  OFFSET 4.5925 91.4895 -427.239
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
   OFFSET 15.7357 0 0
   CHANNELS 3 Zrotation Xrotation Yrotation
   End Site
   {
    OFFSET 20 0 0
   }
  }
 }
}
MOTION
Frames: 2
Frame Time: 0.0333333
0 0 0 0 0 0 10 90 -400 90 0 0 5 0 0
0 0 0 0 0 0 12 94 -398 90 3 0 7 0 1
";

#[test]
fn the_root_offset_moves_over_the_origin_and_the_motion_stays() {
    let motion = parse_bvh(BANDAI_LIKE).unwrap();
    let moved = with_rest_at_origin(&motion);
    let hips = &moved.skeleton.joints[1];
    assert_eq!(hips.offset.x, 0.0);
    assert_eq!(hips.offset.z, 0.0);
    assert!(
        (hips.offset.y - 92.0).abs() < 1e-9,
        "mean hip height: {}",
        hips.offset.y
    );
    assert_eq!(
        moved.skeleton.joints[0].offset,
        motion.skeleton.joints[0].offset
    );
    assert_eq!(
        moved.skeleton.joints[2].offset,
        motion.skeleton.joints[2].offset
    );
    assert_eq!(moved.frames, motion.frames);
    let again = parse_bvh(&to_bvh_string(&moved)).unwrap();
    for f in 0..2 {
        let a = motion.skeleton.joint_positions(motion.frame(f));
        let b = again.skeleton.joint_positions(again.frame(f));
        for (x, y) in a.iter().zip(&b) {
            assert!(x.distance(*y) < 1e-5, "frame {f}: {x} vs {y}");
        }
    }
}

#[test]
fn a_root_without_position_channels_is_left_alone() {
    let text = "HIERARCHY\nROOT Hips\n{\n OFFSET 1 2 3\n CHANNELS 3 Zrotation Xrotation Yrotation\n End Site\n {\n  OFFSET 0 1 0\n }\n}\nMOTION\nFrames: 1\nFrame Time: 0.01\n0 0 0\n";
    let motion = parse_bvh(text).unwrap();
    assert_eq!(with_rest_at_origin(&motion), motion);
}
