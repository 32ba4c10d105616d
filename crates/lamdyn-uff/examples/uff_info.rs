//! Lists and reads UFF files: `cargo run -p lamdyn-uff --example uff_info -- FILE...`
//! (the CLI's `lamdyn uff info` does the same with tables).

fn main() {
    for path in std::env::args().skip(1) {
        match lamdyn_uff::read_path(
            std::path::Path::new(&path),
            lamdyn_uff::ReadOptions {
                lenient_counts: std::env::var_os("LENIENT").is_some(),
            },
        ) {
            Ok(f) => {
                let kinds: Vec<String> = f
                    .datasets
                    .iter()
                    .map(|d| {
                        format!(
                            "{}{}",
                            match &d.dataset {
                                lamdyn_uff::Dataset::Function(_) => "58",
                                lamdyn_uff::Dataset::NodalData(_) => "55",
                                lamdyn_uff::Dataset::Header(_) => "151",
                                lamdyn_uff::Dataset::Units(_) => "164",
                                lamdyn_uff::Dataset::Nodes(n) =>
                                    if n.dataset == 15 {
                                        "15"
                                    } else {
                                        "2411"
                                    },
                                lamdyn_uff::Dataset::Elements(_) => "2412",
                                lamdyn_uff::Dataset::TraceLine(_) => "82",
                                lamdyn_uff::Dataset::CoordinateSystems(_) => "cs",
                            },
                            if d.binary { "b" } else { "" }
                        )
                    })
                    .collect();
                println!(
                    "OK   {path}: {} | skipped {}",
                    kinds.join(" "),
                    f.notices.len()
                );
            }
            Err(e) => println!("ERR  {e}"),
        }
    }
}
