// Temporary probe (not committed): renders dataset samples with given weights, the sample's
// albedo target beside the network image.
use rendernet::data::{Dataset, Split};
use rendernet::nn::render::Renderer;
use rendernet::nn::rendernet::Preset;
use rendernet::Gpu;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (data, weights, out, split) = (&a[1], &a[2], &a[3], if a.get(4).map(|s| s.as_str()) == Some("train") { Split::Train } else { Split::Test });
    let gpu = Gpu::new().unwrap();
    let ds = Dataset::open(data).unwrap();
    let bytes = std::fs::read(weights).unwrap();
    let c3: Vec<usize> = std::env::var("C3").unwrap_or("8,16".into()).split(',').map(|s| s.parse().unwrap()).collect();
    let preset = Preset { name: "tiny-c16", c3: [c3[0], c3[1]], ..Preset::tiny() };
    let mut r = Renderer::new(&gpu, preset, &bytes, weights, 128).unwrap();
    let sv = ds.split(split);
    for (k, i) in sv.spread(4).enumerate() {
        let s = sv.get(i).unwrap();
        let img = r.render(&gpu, &s.grid, &s.view, &s.light).unwrap();
        img.save_png(format!("{out}-{k}-net.png")).unwrap();
        s.images["phong"].save_png(format!("{out}-{k}-ref.png")).unwrap();
    }
}
