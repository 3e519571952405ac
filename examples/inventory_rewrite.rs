//! Size of a Parquet table as this build writes it (issue 34 Build 3, disk): `cargo run
//! --release --example inventory_rewrite -- IN.parquet OUT.parquet` reads a tree inventory or
//! regeneration table (by its name: `*_regeneration.parquet` is the regeneration layer) of any
//! earlier Sylva, writes its rows again with `sylva::output::parquet::csv_to_parquet` (from the
//! CSV text Sylva writes, as a run does), checks that every column reads back equal, and prints
//! the sizes of both files by column (compressed bytes of the column chunks) and the write time.
//! The point geometry is rebuilt from the input's `geo` key (projected CRS: origin = bbox
//! minimum − the least `x_m`, `y_m`; EPSG code from `sylva:epsg`).
use parquet::file::reader::{FileReader, SerializedFileReader};
use std::fmt::Write as _;
use std::path::Path;
use sylva::output::parquet::{self as pq, Kind, Table, INVENTORY, REGENERATION};

fn sizes(path: &Path) -> (u64, Vec<(String, i64)>) {
    let r = SerializedFileReader::new(std::fs::File::open(path).unwrap()).unwrap();
    let md = r.metadata();
    let mut cols: Vec<(String, i64)> = Vec::new();
    for g in md.row_groups() {
        for c in g.columns() {
            let name = c.column_path().string();
            match cols.iter_mut().find(|x| x.0 == name) {
                Some(x) => x.1 += c.compressed_size(),
                None => cols.push((name, c.compressed_size())),
            }
        }
    }
    (std::fs::metadata(path).unwrap().len(), cols)
}

fn csv_of(c: &pq::Columns, t: &Table) -> String {
    let mut s = t.header();
    s.push('\n');
    let (mut ki, mut ks, mut kd, mut kf) = (vec![], vec![], vec![], vec![]);
    for col in t.columns {
        match col.kind {
            Kind::Int64 => ki.push(c.int(col.name).unwrap()),
            Kind::Utf8 => ks.push(c.text(col.name).unwrap()),
            Kind::Double => kd.push(c.double(col.name).unwrap()),
            Kind::Float => kf.push(c.float(col.name).unwrap()),
        }
    }
    for i in 0..c.rows {
        let (mut a, mut b, mut d, mut f) = (0, 0, 0, 0);
        for (k, col) in t.columns.iter().enumerate() {
            if k > 0 {
                s.push(',');
            }
            match col.kind {
                Kind::Int64 => {
                    let _ = write!(s, "{}", ki[a][i]);
                    a += 1;
                }
                Kind::Utf8 => {
                    s.push_str(&ks[b][i]);
                    b += 1;
                }
                Kind::Double => {
                    let _ = write!(s, "{:.*}", col.decimals, kd[d][i]);
                    d += 1;
                }
                Kind::Float => {
                    let _ = write!(s, "{:.*}", col.decimals, kf[f][i]);
                    f += 1;
                }
            }
        }
        s.push('\n');
    }
    s
}

fn main() {
    let a: Vec<String> = std::env::args().skip(1).collect();
    if a.len() != 2 {
        eprintln!("usage: inventory_rewrite IN.parquet OUT.parquet");
        std::process::exit(2);
    }
    let (inp, out) = (Path::new(&a[0]), Path::new(&a[1]));
    let table = if a[0].ends_with("_regeneration.parquet") { &REGENERATION } else { &INVENTORY };
    let c = pq::read_table(inp, table).unwrap();
    let geo: serde_json::Value = serde_json::from_str(&pq::geo_key(inp).unwrap().expect("a geo key")).unwrap();
    let col = &geo["columns"]["geometry"];
    let min = |n: &str| c.double(n).unwrap().iter().cloned().fold(f64::INFINITY, f64::min);
    let bbox = col["bbox"].as_array().unwrap();
    let g = sylva::output::georef::PointGeoRef { x0: bbox[0].as_f64().unwrap() - min("x_m"), y0: bbox[1].as_f64().unwrap() - min("y_m"), per_m: (1.0, 1.0), epsg: col["sylva:epsg"].as_u64().map(|e| e as u32), degrees: false };
    let csv = csv_of(&c, table);
    let t = std::time::Instant::now();
    pq::csv_to_parquet(csv.as_bytes(), "rewrite", out, table, &g).unwrap();
    let write_s = t.elapsed().as_secs_f64();
    let t = std::time::Instant::now();
    let back = pq::read_table(out, table).unwrap();
    let read_s = t.elapsed().as_secs_f64();
    assert_eq!(back.rows, c.rows);
    assert!(back.ints == c.ints && back.texts == c.texts && back.floats == c.floats, "columns differ");
    assert!(back.doubles.iter().zip(&c.doubles).all(|(x, y)| x.0 == y.0 && x.1.iter().zip(&y.1).all(|(p, q)| p.to_bits() == q.to_bits())), "doubles differ");
    let (si, ci) = sizes(inp);
    let (so, co) = sizes(out);
    println!("{} rows; every column reads back equal; write {write_s:.2} s, read {read_s:.2} s", c.rows);
    println!("| column | {} | {} |\n|---|---|---|", inp.display(), out.display());
    for (name, b) in &ci {
        let o = co.iter().find(|x| &x.0 == name).map(|x| x.1).unwrap_or(0);
        println!("| {name} | {:.2} MB | {:.2} MB |", *b as f64 / 1e6, o as f64 / 1e6);
    }
    println!("| file | {:.2} MB | {:.2} MB |", si as f64 / 1e6, so as f64 / 1e6);
}
