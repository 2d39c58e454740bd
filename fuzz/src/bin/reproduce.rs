//! Runs saved inputs through a target without AFL: `reproduce <target> <file or dir>...`.
//! A crash panics here with the message and backtrace the fuzzer's abort hides.

use std::path::Path;

fn main() {
    let mut args = std::env::args().skip(1);
    let Some(name) = args.next() else {
        eprintln!("usage: reproduce <target> <file or dir>...");
        std::process::exit(2);
    };
    let Some(run) = naadf_fuzz::target(&name) else {
        eprintln!("unknown target {name}");
        std::process::exit(2);
    };
    let mut n = 0;
    for arg in args {
        let p = Path::new(&arg);
        let files: Vec<_> = if p.is_dir() {
            let mut v: Vec<_> = std::fs::read_dir(p)
                .expect("readable directory")
                .map(|e| e.expect("directory entry").path())
                .filter(|p| p.is_file())
                .collect();
            v.sort();
            v
        } else {
            vec![p.to_owned()]
        };
        for f in files {
            let data = std::fs::read(&f).expect("readable input");
            eprintln!("{}", f.display());
            run(&data);
            n += 1;
        }
    }
    eprintln!("{n} inputs ran without a crash");
}
