//! VTK and CSV export: `scg replay REC.mcap --vtk DIR --frames-csv DIR` writes files whose
//! numbers read back to the recorded values bit for bit (checked here by parsing the text;
//! the interop check reads the same files with meshio).

use std::path::Path;
use std::process::Command;

/// The numbers of the `DataArray` named `name` in a `.vtu` text.
fn array(text: &str, name: &str) -> Vec<f64> {
    let tag = format!("Name=\"{name}\"");
    let start = text.find(&tag).unwrap_or_else(|| panic!("no {name}"));
    let body = &text[start..];
    let body = &body[body.find('>').unwrap() + 1..body.find("</DataArray>").unwrap()];
    body.split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect()
}

#[test]
fn replay_writes_vtk_and_csv_that_read_back_bit_for_bit() {
    let mcap = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/golden.mcap");
    let dir = tempfile::tempdir().unwrap();
    let (vtk, csv) = (dir.path().join("vtk"), dir.path().join("csv"));
    let out = Command::new(env!("CARGO_BIN_EXE_scg"))
        .arg("replay")
        .arg(&mcap)
        .arg("--vtk")
        .arg(&vtk)
        .arg("--frames-csv")
        .arg(&csv)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rec = scg::record::read_mcap(&mcap).unwrap();
    let pvd = std::fs::read_to_string(vtk.join("golden.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet ").count(), rec.frames.len());
    assert!(vtk.join("golden_geometry.vtu").is_file());
    let mut points = 0;
    for f in &rec.frames {
        let text = std::fs::read_to_string(vtk.join(format!("golden_{:09}.vtu", f.step))).unwrap();
        assert!(pvd.contains(&format!("timestep=\"{}\"", f.time)));
        let xyz: Vec<f64> = f.position.iter().flatten().copied().collect();
        let v: Vec<f64> = f.velocity.iter().flatten().copied().collect();
        let bits = |a: &[f64]| a.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&array(&text, "Points")), bits(&xyz), "step {}", f.step);
        assert_eq!(bits(&array(&text, "velocity")), bits(&v));
        assert_eq!(bits(&array(&text, "diameter")), bits(&f.diameter));
        let ids: Vec<f64> = f.id.iter().map(|&i| i as f64).collect();
        assert_eq!(array(&text, "id"), ids);
        // CSV: one row per particle, the same numbers.
        let rows = std::fs::read_to_string(csv.join(format!("golden_{:09}.csv", f.step))).unwrap();
        let lines: Vec<&str> = rows.lines().collect();
        assert_eq!(lines[0], "id,group,x,y,z,vx,vy,vz,diameter,density");
        assert_eq!(lines.len(), f.len() + 1);
        for (k, line) in lines[1..].iter().enumerate() {
            let c: Vec<&str> = line.split(',').collect();
            assert_eq!(c[0].parse::<u32>().unwrap(), f.id[k]);
            let x: f64 = c[2].parse().unwrap();
            assert_eq!(x.to_bits(), f.position[k][0].to_bits());
            let rho: f64 = c[9].parse().unwrap();
            assert_eq!(rho.to_bits(), f.density[k].to_bits());
        }
        points += f.len();
    }
    assert!(points > 1000, "{points} points checked");
}
