mod camera;
mod scene;
mod viewer;
