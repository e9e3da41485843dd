mod camera;
mod scene;
