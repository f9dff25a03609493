// Generates the parser from `grammar/*.lalrpop` into OUT_DIR (never
// committed); `lang::parser` includes it with `lalrpop_mod!`.
fn main() {
    let out_dir = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR");
    lalrpop::Configuration::new()
        .set_in_dir("grammar")
        .set_out_dir(out_dir)
        .process()
        .unwrap_or_else(|e| panic!("lalrpop failed: {e}"));
    println!("cargo:rerun-if-changed=grammar");
}
