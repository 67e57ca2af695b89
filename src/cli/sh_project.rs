//! `sh-project`: clap arguments → [`sh::stage::Config`] → one library call → outputs.
//!
//! [`sh::stage::Config`]: crate::sh::stage::Config

mod args;

use super::common::{Context, Outcome, Stage};
use super::options::{check_json_output, Execution};
use super::outputs::{check_outputs, Holds, Outputs};
use crate::io::Output;
use crate::limits::MAX_EPSILON_ORDER;
use crate::sh::project::OrderChoice;
use crate::sh::stage::{self, Config};
use crate::sh::window::Window;
use anyhow::Result;
pub use args::*;

impl TryFrom<&Args> for Config {
    type Error = anyhow::Error;
    fn try_from(args: &Args) -> Result<Config> {
        let order = match (args.order, args.epsilon) {
            (Some(order), _) => OrderChoice::Order(order),
            (None, Some(epsilon)) => OrderChoice::Epsilon { epsilon, max_search: MAX_EPSILON_ORDER },
            (None, None) => OrderChoice::Order(2),
        };
        Ok(Config {
            order,
            reconstruction: !args.reconstruct.is_empty(),
            irradiance: !args.irradiance.is_empty(),
            size: args.size,
            window: args.window.unwrap_or(Window::Lanczos),
            irradiance_window: args.window.unwrap_or(Window::Nonneg),
            source: args.input.name(),
            args: std::env::args().collect(),
        })
    }
}

impl Stage for Args {
    const NAME: &'static str = "sh-project";
    fn execution(&self) -> &Execution {
        &self.run
    }
    fn run(self, ctx: &Context) -> Result<Outcome> {
        check_json_output(&self.output, self.json)?;
        let images = self.reconstruct.iter().chain(&self.irradiance).map(|o| (o, Holds::Image));
        check_outputs(std::iter::once((&self.output, Holds::Text)).chain(images))?;
        let config = Config::try_from(&self)?;
        let map = self.input.load(ctx)?;
        let out = stage::run(&config, &map, ctx.progress())?;

        let mut outputs = Outputs::new();
        for (images, image) in [(&self.reconstruct, &out.reconstruction), (&self.irradiance, &out.irradiance)] {
            for (path, image) in images.iter().zip(std::iter::repeat(image).flatten()) {
                outputs.image(path, image, self.exposure.stops)?;
            }
        }
        outputs.json(&self.output, &out.document)?;
        if self.json {
            outputs.json(&Output::Stdout, &out.summary)?;
        }
        outputs.commit()?;
        Ok(Outcome::Success)
    }
}
